#include "harness.hpp"

#include <unistd.h>

#include <cmath>
#include <cstring>

namespace bm {

namespace {

const char* g_section = "";
int g_checks = 0;
int g_failed = 0;

// One output line is built here, then written at once.
class Line {
 public:
  Line& str(const char* s) {
    while (*s != '\0' && len_ < sizeof buf_ - 2) buf_[len_++] = *s++;
    return *this;
  }
  Line& ch(char c) {
    if (len_ < sizeof buf_ - 2) buf_[len_++] = c;
    return *this;
  }
  Line& u(std::uint64_t v) {
    char d[24];
    int n = 0;
    do {
      d[n++] = static_cast<char>('0' + v % 10U);
      v /= 10U;
    } while (v != 0U);
    while (n > 0) ch(d[--n]);
    return *this;
  }
  Line& i(std::int64_t v) {
    if (v < 0) {
      ch('-');
      return u(0U - static_cast<std::uint64_t>(v));
    }
    return u(static_cast<std::uint64_t>(v));
  }
  Line& hex(std::uint64_t v, int digits) {
    str("0x");
    for (int k = digits - 1; k >= 0; --k) ch("0123456789abcdef"[(v >> (4 * k)) & 0xFU]);
    return *this;
  }
  // About nine significant digits, for people; the hex bits are what is compared.
  Line& approx(double v) {
    if (std::isnan(v)) return str("nan");
    if (v < 0.0) {
      ch('-');
      v = -v;
    }
    if (std::isinf(v)) return str("inf");
    if (v == 0.0) return str("0");
    int e = static_cast<int>(std::floor(std::log10(v)));
    auto digits = static_cast<std::uint64_t>(std::llround(v / std::pow(10.0, e) * 1e8));
    if (digits >= 1000000000ULL) {
      digits /= 10U;
      ++e;
    }
    char d[9];
    for (int k = 8; k >= 0; --k) {
      d[k] = static_cast<char>('0' + digits % 10U);
      digits /= 10U;
    }
    ch(d[0]).ch('.');
    for (int k = 1; k < 9; ++k) ch(d[k]);
    ch('e');
    return i(e);
  }
  void emit() {
    buf_[len_++] = '\n';
    std::size_t done = 0;
    while (done < len_) {
      const ssize_t n = ::write(1, buf_ + done, len_ - done);
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
    len_ = 0;
  }

 private:
  char buf_[256];
  std::size_t len_ = 0;
};

Line& name_line(Line& l, char kind, const char* name) {
  return l.ch(kind).ch(' ').str(g_section).ch('.').str(name).ch(' ');
}

bool record(bool ok) {
  ++g_checks;
  if (!ok) ++g_failed;
  return ok;
}

Line& fail_line(Line& l, const char* expr, const char* file, int line) {
  const char* base = std::strrchr(file, '/');
  return l.str("FAIL ").str(base != nullptr ? base + 1 : file).ch(':').i(line).str(": ").str(expr);
}

}  // namespace

void out(const char* text) {
  Line l;
  l.str(text).emit();
}

void begin_section(const char* name) {
  g_section = name;
  g_checks = 0;
  g_failed = 0;
}

int end_section() {
  Line l;
  if (g_failed == 0) {
    l.str("ok ").str(g_section).str(": ").i(g_checks).str(" checks").emit();
  } else {
    l.str("FAIL ").str(g_section).str(": ").i(g_failed).str(" of ").i(g_checks);
    l.str(" checks failed").emit();
  }
  return g_failed;
}

bool check(bool ok, const char* expr, const char* file, int line) {
  if (!record(ok)) {
    Line l;
    fail_line(l, expr, file, line).emit();
  }
  return ok;
}

bool check_eq(std::int64_t got, std::int64_t want, const char* expr, const char* file, int line) {
  const bool ok = got == want;
  if (!record(ok)) {
    Line l;
    fail_line(l, expr, file, line).str(" (got ").i(got).str(", want ").i(want).ch(')').emit();
  }
  return ok;
}

bool check_near(double got, double want, double tolerance, const char* expr, const char* file,
                int line) {
  const bool ok = std::fabs(got - want) <= tolerance;  // false for NaN
  if (!record(ok)) {
    Line l;
    fail_line(l, expr, file, line).str(" (got ").approx(got).str(", want ").approx(want);
    l.str(" +- ").approx(tolerance).ch(')').emit();
  }
  return ok;
}

namespace {

void double_line(char kind, const char* name, double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  Line l;
  name_line(l, kind, name).hex(bits, 16).ch(' ').approx(v).emit();
}

}  // namespace

void value(const char* name, double v) {
  double_line('v', name, v);
}

void value_trig(const char* name, double v) {
  double_line('t', name, v);
}

void value_f(const char* name, float v) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  Line l;
  name_line(l, 'v', name).hex(bits, 8).ch(' ').approx(static_cast<double>(v)).emit();
}

void value_u(const char* name, std::uint64_t v) {
  Line l;
  name_line(l, 'v', name).hex(v, 16).ch(' ').u(v).emit();
}

void info_u(const char* name, std::uint64_t v) {
  Line l;
  name_line(l, 'i', name).u(v).emit();
}

#if defined(HARMOLOC_BAREMETAL_TARGET)

namespace {

// 64 KiB below the caller; the deepest kernel, the harmonic query, needs about 16 KiB.
constexpr std::size_t kPaintWords = 16 * 1024;
constexpr std::uint32_t kPaint = 0xDEADBEEFU;

}  // namespace

// Not inlined, so its own frame sits above the painted region and the measured depth is the
// callee's plus one call.
__attribute__((noinline)) std::size_t stack_used(void (*fn)(void*), void* context) {
  std::uint32_t* sp = nullptr;
  __asm__ volatile("mov %0, sp" : "=r"(sp));
  volatile std::uint32_t* const bottom = sp - kPaintWords;
  for (std::size_t k = 0; k < kPaintWords; ++k) bottom[k] = kPaint;
  fn(context);
  std::size_t k = 0;
  while (k < kPaintWords && bottom[k] == kPaint) ++k;
  return (kPaintWords - k) * sizeof(std::uint32_t);
}

#else

std::size_t stack_used(void (*fn)(void*), void* context) {
  fn(context);
  return 0;
}

#endif

}  // namespace bm
