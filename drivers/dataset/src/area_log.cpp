#include "harmoloc/dataset/area_log.hpp"

#include <cerrno>
#include <cinttypes>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "harmoloc/algorithms/crc32.hpp"
#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::dataset {

namespace {

constexpr const char* kMagic = "# harmoloc area log v1";
// The optional column after the boards (added after v1's first release; a log without it still
// reads), and the optional columns after it: each board's column sum, then its side pixels
// (added later still; AreaVector::column_sum, side_pixels), and after those each board's row sum
// (AreaVector::row_sum, added last; a log with columns but no rows still reads).
constexpr const char* kDistrustColumn = "distrusted_mask";
constexpr const char* kColumnSumPrefix = "column_sum_";
constexpr const char* kSidePrefix = "side_px_";
constexpr const char* kRowSumPrefix = "row_sum_";

[[noreturn]] void fail(const std::string& path, std::size_t line, const std::string& what) {
  throw std::runtime_error(path + ":" + std::to_string(line) + ": " + what);
}

bool parse_u64(const std::string& text, std::uint64_t& out) {
  if (text.empty() || text.size() > 20) return false;
  for (char c : text) {
    if (c < '0' || c > '9') return false;
  }
  errno = 0;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
  if (errno == ERANGE || end != text.c_str() + text.size()) return false;
  out = v;
  return true;
}

// "key=value" from the header's second line.
bool header_value(const std::string& line, const std::string& key, std::string& value) {
  std::istringstream s(line.substr(1));
  std::string item;
  while (s >> item) {
    if (item.compare(0, key.size() + 1, key + "=") == 0) {
      value = item.substr(key.size() + 1);
      return true;
    }
  }
  return false;
}

}  // namespace

std::uint32_t thresholds_fingerprint(const algorithms::ThresholdSet& thresholds) {
  // Text, not the struct's bytes: the same on every build and architecture.
  std::string text;
  char item[96];
  for (std::size_t k = 0; k < thresholds.count; ++k) {
    const auto& b = thresholds.boards[k];
    std::snprintf(item, sizeof item, "%.6g,%.6g,%u,%u,%u;", static_cast<double>(b.hue_min_deg),
                  static_cast<double>(b.hue_max_deg), b.saturation_min, b.value_min, b.value_max);
    text += item;
  }
  return algorithms::crc32(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

AreaLog read_area_log(const std::string& path) {
  std::string content;
  if (const std::string e =
          drivers::read_regular_file(path, drivers::input_limits::kRecordingBytes, content);
      !e.empty()) {
    throw std::runtime_error(path + ": cannot read: " + e);
  }
  std::istringstream in(content);
  AreaLog log;
  std::string line;
  std::size_t n = 0;
  if (!std::getline(in, line) || line.compare(0, std::strlen(kMagic), kMagic) != 0) {
    fail(path, 1, "not an area log (first line must start with '" + std::string(kMagic) + "')");
  }
  ++n;
  if (!std::getline(in, line) || line.empty() || line[0] != '#') {
    fail(path, 2, "missing the '# width_px=... height_px=... thresholds_crc32=...' line");
  }
  ++n;
  std::string w, h, c;
  std::uint64_t wv = 0, hv = 0;
  if (!header_value(line, "width_px", w) || !header_value(line, "height_px", h) ||
      !header_value(line, "thresholds_crc32", c) || !parse_u64(w, wv) || !parse_u64(h, hv) ||
      wv == 0 || hv == 0 || wv > 16384 || hv > 16384) {
    fail(path, n, "needs width_px and height_px (1..16384) and thresholds_crc32");
  }
  char* end = nullptr;
  errno = 0;
  const unsigned long crc = std::strtoul(c.c_str(), &end, 16);
  if (c.size() < 3 || c.compare(0, 2, "0x") != 0 || errno != 0 || *end != '\0' ||
      crc > 0xFFFFFFFFUL) {
    fail(path, n, "thresholds_crc32 must be a hexadecimal 0x........ value");
  }
  log.image_width_px = static_cast<std::uint32_t>(wv);
  log.image_height_px = static_cast<std::uint32_t>(hv);
  log.thresholds_crc32 = static_cast<std::uint32_t>(crc);

  if (!std::getline(in, line)) fail(path, n + 1, "missing the column header");
  ++n;
  {
    std::istringstream s(line);
    std::string col;
    std::getline(s, col, ',');
    if (col != "timestamp_ns") fail(path, n, "first column must be timestamp_ns");
    std::vector<std::string> after;  // the columns after distrusted_mask
    while (std::getline(s, col, ',')) {
      if (col.empty()) fail(path, n, "empty board name in the column header");
      if (log.has_distrust) {
        after.push_back(col);
      } else if (col == kDistrustColumn) {
        log.has_distrust = true;
      } else {
        log.board_names.push_back(col);
      }
    }
    if (log.board_names.empty() || log.board_names.size() > algorithms::kMaxBoards) {
      fail(path, n, "needs 1 to " + std::to_string(algorithms::kMaxBoards) + " board columns");
    }
    if (!after.empty()) {
      std::vector<std::string> expected;
      for (const std::string& b : log.board_names) expected.push_back(kColumnSumPrefix + b);
      for (const std::string& b : log.board_names) expected.push_back(kSidePrefix + b);
      std::vector<std::string> with_rows = expected;
      for (const std::string& b : log.board_names) with_rows.push_back(kRowSumPrefix + b);
      if (after != expected && after != with_rows) {
        fail(path, n,
             "after distrusted_mask: expected " + std::string(kColumnSumPrefix) + "<board>, then " +
                 kSidePrefix + "<board> and optionally " + kRowSumPrefix +
                 "<board> for every board, in order");
      }
      log.has_columns = true;
      log.has_rows = after == with_rows;
    }
  }
  const std::uint64_t max_area = wv * hv;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    std::istringstream s(line);
    std::string field;
    std::uint64_t t = 0;
    if (!std::getline(s, field, ',') || !parse_u64(field, t)) fail(path, n, "bad timestamp");
    if (!log.timestamp_ns.empty() && t <= log.timestamp_ns.back()) {
      fail(path, n, "timestamps must increase");
    }
    algorithms::AreaVector a;
    a.count = log.board_names.size();
    for (std::size_t k = 0; k < a.count; ++k) {
      std::uint64_t v = 0;
      if (!std::getline(s, field, ',') || !parse_u64(field, v) || v > max_area) {
        fail(path, n, "board " + std::to_string(k + 1) + ": not a pixel count within the frame");
      }
      a.pixels[k] = static_cast<std::uint32_t>(v);
    }
    if (log.has_distrust) {
      std::uint64_t mask = 0;
      if (!std::getline(s, field, ',') || !parse_u64(field, mask) ||
          mask >= (std::uint64_t{1} << a.count)) {
        fail(path, n, "distrusted_mask: not a bit mask of the boards");
      }
      log.distrusted_mask.push_back(static_cast<std::uint32_t>(mask));
    }
    if (log.has_columns) {
      // A pixel's column is below the width and its row below the height; a side pixel is one of
      // the board's pixels, in the first or last column of a row.
      const std::size_t fields = (log.has_rows ? 3U : 2U) * a.count;
      std::vector<std::string> f;
      while (f.size() <= fields && std::getline(s, field, ',')) f.push_back(field);
      if (f.size() > fields) fail(path, n, "more columns than boards");
      // The columns' and sides' fields are all '-' (not measured) or all numbers, and so are the
      // rows' fields; rows are measured only where columns are.
      const auto all_dashes = [&f](std::size_t from, std::size_t to) {
        for (std::size_t i = from; i < to; ++i) {
          if (i >= f.size() || f[i] != "-") return false;
        }
        return true;
      };
      const bool unmeasured = all_dashes(0, 2U * a.count);
      const bool rows_unmeasured = !log.has_rows || all_dashes(2U * a.count, fields);
      if (unmeasured && !rows_unmeasured) {
        fail(path, n, "row sums given for a frame whose column sums are '-'");
      }
      for (std::size_t k = 0; !unmeasured && k < a.count; ++k) {
        std::uint64_t v = 0;
        if (k >= f.size() || !parse_u64(f[k], v) || v > std::uint64_t{a.pixels[k]} * (wv - 1U)) {
          fail(path, n,
               kColumnSumPrefix + log.board_names[k] +
                   ": not a sum of columns of the board's pixels within the width");
        }
        a.column_sum[k] = v;
      }
      for (std::size_t k = 0; !unmeasured && k < a.count; ++k) {
        std::uint64_t v = 0;
        if (a.count + k >= f.size() || !parse_u64(f[a.count + k], v) || v > a.pixels[k] ||
            v > 2U * hv) {
          fail(path, n,
               kSidePrefix + log.board_names[k] +
                   ": more side pixels than the board's pixels or the frame's two sides hold");
        }
        a.side_pixels[k] = static_cast<std::uint32_t>(v);
      }
      for (std::size_t k = 0; !rows_unmeasured && k < a.count; ++k) {
        std::uint64_t v = 0;
        if (2U * a.count + k >= f.size() || !parse_u64(f[2U * a.count + k], v) ||
            v > std::uint64_t{a.pixels[k]} * (hv - 1U)) {
          fail(path, n,
               kRowSumPrefix + log.board_names[k] +
                   ": not a sum of rows of the board's pixels within the height");
        }
        a.row_sum[k] = v;
      }
      if (!unmeasured) a.width_px = log.image_width_px;
      if (!rows_unmeasured) a.height_px = log.image_height_px;
    }
    if (std::getline(s, field, ',')) fail(path, n, "more columns than boards");
    log.timestamp_ns.push_back(t);
    log.areas.push_back(a);
  }
  if (log.areas.empty()) fail(path, n, "no frames");
  return log;
}

bool AreaLogWriter::open(const std::string& path, std::uint32_t width_px, std::uint32_t height_px,
                         const algorithms::ThresholdSet& thresholds,
                         const std::vector<std::string>& board_names) {
  if (!out_.open(path)) return false;
  std::FILE* f = out_.file();
  boards_ = thresholds.count;
  std::fprintf(f, "%s: pixels of each board per frame\n", kMagic);
  std::fprintf(f, "# width_px=%u height_px=%u thresholds_crc32=0x%08x\n", width_px, height_px,
               thresholds_fingerprint(thresholds));
  std::fputs("timestamp_ns", f);
  for (std::size_t k = 0; k < boards_; ++k) {
    if (k < board_names.size() && !board_names[k].empty()) {
      std::fprintf(f, ",%s", board_names[k].c_str());
    } else {
      std::fprintf(f, ",board%zu", k + 1);
    }
  }
  std::fprintf(f, ",%s", kDistrustColumn);
  for (const char* prefix : {kColumnSumPrefix, kSidePrefix, kRowSumPrefix}) {
    for (std::size_t k = 0; k < boards_; ++k) {
      if (k < board_names.size() && !board_names[k].empty()) {
        std::fprintf(f, ",%s%s", prefix, board_names[k].c_str());
      } else {
        std::fprintf(f, ",%sboard%zu", prefix, k + 1);
      }
    }
  }
  std::fputc('\n', f);
  return std::ferror(f) == 0;
}

void AreaLogWriter::write(std::uint64_t t_ns, const algorithms::AreaVector& areas,
                          std::uint32_t distrusted_mask) {
  if (!out_.is_open()) return;
  // 20 digits of time, and per board (8 at most) 10 of pixels, 20 of column sum, 10 of sides and
  // 20 of row sum, each with its comma.
  char line[768];
  int n = std::snprintf(line, sizeof line, "%" PRIu64, t_ns);
  for (std::size_t k = 0; k < boards_ && n > 0 && static_cast<std::size_t>(n) < sizeof line; ++k) {
    n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), ",%" PRIu32,
                       k < areas.count ? areas.pixels[k] : 0U);
  }
  if (n > 0 && static_cast<std::size_t>(n) < sizeof line) {
    const std::uint32_t boards_bits =
        boards_ >= 32 ? 0xFFFFFFFFU : (std::uint32_t{1} << boards_) - 1U;
    n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), ",%" PRIu32,
                       distrusted_mask & boards_bits);
  }
  // Areas whose columns were not measured (width_px 0) write '-' in the column fields: a 0 would
  // read back as a centroid in column 0.
  const bool columns = areas.columns_measured();
  for (std::size_t k = 0; k < boards_ && n > 0 && static_cast<std::size_t>(n) < sizeof line; ++k) {
    if (!columns) {
      n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), ",-");
      continue;
    }
    n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), ",%" PRIu64,
                       k < areas.count ? areas.column_sum[k] : std::uint64_t{0});
  }
  for (std::size_t k = 0; k < boards_ && n > 0 && static_cast<std::size_t>(n) < sizeof line; ++k) {
    if (!columns) {
      n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), ",-");
      continue;
    }
    n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), ",%" PRIu32,
                       k < areas.count ? areas.side_pixels[k] : 0U);
  }
  // Rows are measured with the columns by every segmentation path; areas with columns but no
  // rows (made by hand, read from an older log) write '-' in all these fields.
  const bool rows = columns && areas.rows_measured();
  for (std::size_t k = 0; k < boards_ && n > 0 && static_cast<std::size_t>(n) < sizeof line; ++k) {
    if (!rows) {
      n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), ",-");
      continue;
    }
    n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), ",%" PRIu64,
                       k < areas.count ? areas.row_sum[k] : std::uint64_t{0});
  }
  if (n <= 0 || static_cast<std::size_t>(n) + 1 >= sizeof line) return;
  line[n++] = '\n';
  out_.append(line, static_cast<std::size_t>(n));
}

}  // namespace harmoloc::dataset
