#pragma once
/// @file A tiny assertion harness for the freestanding kernel tests. No heap, no printf (newlib's
/// float formatting allocates), no exceptions, so one test program runs unchanged on the host
/// and on the emulated Cortex-M7. Output, one line each:
///   v <name> <hex bits> <decimal>   a result that must be bit-identical on host and target
///   t <name> <hex bits> <decimal>   a result through sin, cos or atan2, whose last bits differ
///                                   between glibc and newlib: equal within a relative 1e-12
///   i <name> <text>                 information that may differ by platform (sizes, stack)
/// compare_outputs.py compares the v and t lines of a host run and a target run.
///   FAIL <file>:<line>: <check> ... a failed check
///   ok <section>: <n> checks        or  FAIL <section>: <k> of <n> checks failed

#include <cstddef>
#include <cstdint>

namespace bm {

/// Writes @p text to standard output (semihosting on the target).
void out(const char* text);

void begin_section(const char* name);
/// Prints the section's summary line; returns its number of failed checks.
int end_section();

bool check(bool ok, const char* expr, const char* file, int line);
bool check_eq(std::int64_t got, std::int64_t want, const char* expr, const char* file, int line);
bool check_near(double got, double want, double tolerance, const char* expr, const char* file,
                int line);

/// A result compared bit for bit between host and target: doubles by their IEEE bits, floats
/// by theirs, integers as they are. Names are prefixed with the section.
void value(const char* name, double v);
void value_f(const char* name, float v);
void value_u(const char* name, std::uint64_t v);
/// A double computed through sin, cos or atan2 (see the t lines above).
void value_trig(const char* name, double v);

/// Information not compared between platforms.
void info_u(const char* name, std::uint64_t v);

/// Stack bytes @p fn(context) used below the caller's frame, measured by painting the stack
/// before the call; 0 where not measured (the host: its libc and ASLR make it meaningless).
std::size_t stack_used(void (*fn)(void*), void* context);

/// Whether this is the build for the emulated core.
constexpr bool kOnTarget =
#if defined(HARMOLOC_BAREMETAL_TARGET)
    true;
#else
    false;
#endif

}  // namespace bm

#define BM_CHECK(e) ::bm::check((e), #e, __FILE__, __LINE__)
#define BM_CHECK_EQ(got, want)                                                    \
  ::bm::check_eq(static_cast<std::int64_t>(got), static_cast<std::int64_t>(want), \
                 #got " == " #want, __FILE__, __LINE__)
#define BM_CHECK_NEAR(got, want, tol) \
  ::bm::check_near((got), (want), (tol), #got " ~ " #want, __FILE__, __LINE__)
