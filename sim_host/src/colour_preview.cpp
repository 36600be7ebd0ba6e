#include "harmoloc/sim_host/colour_preview.hpp"
#include "harmoloc/sim_host/svg.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <zlib.h>

#include "harmoloc/sim_host/line_chart.hpp"

namespace harmoloc::sim_host::colours {

namespace {

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

void put_chunk(std::vector<std::uint8_t>& out, const char* type,
               const std::vector<std::uint8_t>& data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  const uLong crc = crc32(0L, out.data() + start, static_cast<uInt>(out.size() - start));
  put_u32(out, static_cast<std::uint32_t>(crc));
}

// A fully saturated colour of hue @p h8 (8-bit steps), as CSS and as bytes.
std::array<std::uint8_t, 3> hue_rgb(int h8) {
  const double h = 2.0 * ((h8 % kHueSteps + kHueSteps) % kHueSteps) / 60.0;
  const double x = 1.0 - std::fabs(std::fmod(h, 2.0) - 1.0);
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(h)) {
    case 0:
      r = 1;
      g = x;
      break;
    case 1:
      r = x;
      g = 1;
      break;
    case 2:
      g = 1;
      b = x;
      break;
    case 3:
      g = x;
      b = 1;
      break;
    case 4:
      r = x;
      b = 1;
      break;
    default:
      r = 1;
      b = x;
      break;
  }
  return {static_cast<std::uint8_t>(255 * r), static_cast<std::uint8_t>(255 * g),
          static_cast<std::uint8_t>(255 * b)};
}

std::string css(const std::array<std::uint8_t, 3>& c) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buf;
}

std::string safe_file_part(const std::string& name) {
  std::string out;
  for (const char c : name) out += std::isalnum(static_cast<unsigned char>(c)) != 0 ? c : '_';
  return out;
}

std::string describe_window(const algorithms::ColourThreshold& w) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "hue %.0f..%.0f deg%s, saturation >= %d, value %d..%d",
                static_cast<double>(w.hue_min_deg), static_cast<double>(w.hue_max_deg),
                w.hue_min_deg > w.hue_max_deg ? " (through 0)" : "", int{w.saturation_min},
                int{w.value_min}, int{w.value_max});
  return buf;
}

}  // namespace

std::vector<std::uint8_t> encode_png(std::uint32_t width, std::uint32_t height, int channels,
                                     const std::vector<std::uint8_t>& pixels) {
  const std::size_t row = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels);
  if (pixels.size() != row * height) throw std::runtime_error("encode_png: wrong pixel count");
  // Filter type 0 (none) before every row, then one zlib stream.
  std::vector<std::uint8_t> raw;
  raw.reserve((row + 1) * height);
  for (std::uint32_t y = 0; y < height; ++y) {
    raw.push_back(0);
    raw.insert(raw.end(), pixels.begin() + static_cast<std::ptrdiff_t>(y * row),
               pixels.begin() + static_cast<std::ptrdiff_t>((y + 1) * row));
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<std::uint8_t> packed(packed_size);
  if (compress2(packed.data(), &packed_size, raw.data(), static_cast<uLong>(raw.size()), 6) != Z_OK)
    throw std::runtime_error("encode_png: zlib failed");
  packed.resize(packed_size);

  std::vector<std::uint8_t> out{0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<std::uint8_t> ihdr;
  put_u32(ihdr, width);
  put_u32(ihdr, height);
  const std::uint8_t colour_type = channels == 1 ? 0 : channels == 3 ? 2 : 6;
  ihdr.insert(ihdr.end(), {8, colour_type, 0, 0, 0});
  put_chunk(out, "IHDR", ihdr);
  put_chunk(out, "IDAT", packed);
  put_chunk(out, "IEND", {});
  return out;
}

void write_png(const std::string& path, std::uint32_t width, std::uint32_t height, int channels,
               const std::vector<std::uint8_t>& pixels) {
  const std::vector<std::uint8_t> bytes = encode_png(width, height, channels, pixels);
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!f) throw std::runtime_error(path + ": cannot write");
}

std::vector<std::uint8_t> mask_rgba(const RgbImage& frame, const algorithms::ThresholdSet& windows,
                                    std::size_t board) {
  const algorithms::BoardClassifier cls(windows);
  const std::size_t n = static_cast<std::size_t>(frame.width_px) * frame.height_px;
  const auto colour = hue_rgb(hue_steps_of(windows.boards[board]).lo_h8 +
                              hue_steps_of(windows.boards[board]).width_h8() / 2 + kHueSteps / 2);
  std::vector<std::uint8_t> out(4 * n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t bits =
        cls.classify(frame.rgb[3 * i], frame.rgb[3 * i + 1], frame.rgb[3 * i + 2]);
    if ((bits & (1U << board)) == 0) continue;
    out[4 * i] = colour[0];
    out[4 * i + 1] = colour[1];
    out[4 * i + 2] = colour[2];
    out[4 * i + 3] = 255;
  }
  return out;
}

std::string write_preview(const std::string& dir, FrameSource& frames, const PreviewInput& in) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const algorithms::ThresholdSet windows = threshold_set_of(in.boards);
  const RunAreas& a = in.areas;
  const std::size_t measured = a.timestamp_ns.size();
  // Which measured frame is which frame of the run (measure_run may have stepped).
  const std::size_t step = measured > 1 ? (frames.size() - 1) / (measured - 1) : 1;
  const auto run_index = [&](std::size_t k) {
    for (std::size_t f = std::min(k * step, frames.size() - 1);; --f) {
      if (frames.timestamp_ns(f) == a.timestamp_ns[k]) return f;
      if (f == 0) break;
    }
    return std::min(k * step, frames.size() - 1);
  };
  // The frames to show: where most boards are in view, then each board's largest.
  std::vector<std::size_t> shown;
  std::size_t best = 0, best_boards = 0;
  std::uint64_t best_total = 0;
  for (std::size_t k = 0; k < measured; ++k) {
    std::size_t in_view = 0;
    std::uint64_t total = 0;
    for (std::size_t b = 0; b < a.boards; ++b) {
      in_view += a.area_px[b][k] > 0 ? 1 : 0;
      total += a.area_px[b][k];
    }
    if (in_view > best_boards || (in_view == best_boards && total > best_total)) {
      best = k;
      best_boards = in_view;
      best_total = total;
    }
  }
  if (measured > 0) shown.push_back(best);
  std::vector<std::size_t> largest(a.boards, 0);
  for (std::size_t b = 0; b < a.boards; ++b) {
    largest[b] = static_cast<std::size_t>(
        std::max_element(a.area_px[b].begin(), a.area_px[b].end()) - a.area_px[b].begin());
    if (std::find(shown.begin(), shown.end(), largest[b]) == shown.end() && measured > 0)
      shown.push_back(largest[b]);
  }

  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>harmoloc-colours: "
       << svg::escape(in.title)
       << "</title>\n<style>body{font-family:sans-serif;margin:1.5em;max-width:1400px}"
          "figure{display:inline-block;margin:0.5em;vertical-align:top}"
          ".stack{position:relative;display:inline-block}"
          ".stack img{display:block;image-rendering:pixelated}"
          ".stack img.mask{position:absolute;left:0;top:0;opacity:0.75}"
          "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 8px}"
          ".warn{color:#a00}</style></head><body>\n<h1>Colour windows: "
       << svg::escape(in.title) << "</h1>\n";
  html << "<h2>Boards</h2>\n<table><tr><th>board</th><th>window (the firmware's)</th>"
          "<th>median area (px)</th><th>largest area (px)</th><th>frames in view</th></tr>\n";
  for (std::size_t b = 0; b < in.boards.size(); ++b) {
    std::vector<std::uint32_t> v = a.area_px[b];
    std::sort(v.begin(), v.end());
    std::size_t seen = 0;
    for (const auto x : v) seen += x > 0 ? 1 : 0;
    const auto swatch = css(hue_rgb(in.boards[b].hue_centre_h8));
    html << "<tr><td><span style=\"background:" << swatch << "\">&nbsp;&nbsp;&nbsp;</span> "
         << svg::escape(in.boards[b].name) << "</td><td>" << describe_window(in.boards[b].window)
         << "</td><td>" << (v.empty() ? 0 : v[v.size() / 2]) << "</td><td>"
         << (v.empty() ? 0 : v.back()) << "</td><td>" << seen << " of " << v.size()
         << "</td></tr>\n";
  }
  html << "</table>\n";
  html << "<h2>Warnings</h2>\n";
  if (in.warnings.empty()) html << "<p>None.</p>\n";
  for (const auto& w : in.warnings) html << "<p class=\"warn\">" << svg::escape(w) << "</p>\n";

  html << "<h2>Masks</h2>\n<p>Each board's pixels (as the firmware counts them) drawn over the "
          "frame in the opposite hue; hover the frame to see it without the masks.</p>\n";
  RgbImage img;
  for (std::size_t idx = 0; idx < shown.size(); ++idx) {
    const std::size_t k = shown[idx];
    const std::size_t f = run_index(k);
    frames.read(f, img);
    const std::string frame_file = "frame-" + std::to_string(f) + ".png";
    write_png((fs::path(dir) / frame_file).string(), img.width_px, img.height_px, 3, img.rgb);
    html << "<h3>Frame " << f << " (t = " << std::fixed;
    html.precision(3);
    html << (static_cast<double>(frames.timestamp_ns(f) - frames.timestamp_ns(0)) * 1e-9) << " s)";
    std::string why = idx == 0 ? "the most boards in view" : "";
    for (std::size_t b = 0; b < a.boards; ++b)
      if (largest[b] == k)
        why += (why.empty() ? "" : "; ") + ("largest area of " + in.boards[b].name);
    html << ": " << svg::escape(why);
    html << "</h3>\n<figure><div class=\"stack\" onmouseover=\"for(const m of "
            "this.querySelectorAll('.mask'))m.style.display='none'\" onmouseout=\"for(const m of "
            "this.querySelectorAll('.mask'))m.style.display='block'\"><img src=\""
         << frame_file << "\" alt=\"frame\">";
    std::vector<std::string> per_board;
    for (std::size_t b = 0; b < a.boards; ++b) {
      const std::string mask_file = "mask-" + std::to_string(f) + "-" + std::to_string(b + 1) +
                                    "-" + safe_file_part(in.boards[b].name) + ".png";
      write_png((fs::path(dir) / mask_file).string(), img.width_px, img.height_px, 4,
                mask_rgba(img, windows, b));
      html << "<img class=\"mask\" src=\"" << mask_file << "\" alt=\"mask\">";
      per_board.push_back(mask_file);
    }
    html << "</div><figcaption>all boards</figcaption></figure>\n";
    for (std::size_t b = 0; b < a.boards; ++b) {
      html << "<figure><div class=\"stack\"><img src=\"" << frame_file
           << "\" alt=\"frame\"><img class=\"mask\" src=\"" << per_board[b]
           << "\" alt=\"mask\"></div><figcaption>" << svg::escape(in.boards[b].name) << ": "
           << a.area_px[b][k] << " px</figcaption></figure>\n";
    }
  }

  if (measured > 1) {
    std::vector<double> t;
    for (const auto ns : a.timestamp_ns)
      t.push_back(static_cast<double>(ns - a.timestamp_ns[0]) * 1e-9);
    std::vector<Series> series;
    for (std::size_t b = 0; b < a.boards; ++b) {
      Series s{in.boards[b].name, css(hue_rgb(in.boards[b].hue_centre_h8)), {}};
      for (const auto px : a.area_px[b])
        s.y.push_back(100.0 * static_cast<double>(px) / static_cast<double>(a.frame_px));
      series.push_back(std::move(s));
    }
    html << "<h2>Areas along the run</h2>\n"
         << line_chart("board areas along the run", "time (s)", "area (% of frame)", t, series,
                       -1.0, "", false)
         << "\n";
  }
  if (!in.clusters.empty()) {
    html << "<h2>Colour clusters of the run</h2>\n<table><tr><th>hue (deg)</th><th>peak</th>"
            "<th>saturated pixels</th><th>verdict</th></tr>\n";
    for (const auto& c : in.clusters) {
      html << "<tr><td><span style=\"background:" << css(hue_rgb(c.peak_h8))
           << "\">&nbsp;&nbsp;&nbsp;</span> " << 2 * c.range.lo_h8 << ".." << 2 * c.range.hi_h8
           << "</td><td>" << 2 * c.peak_h8 << "</td><td>" << static_cast<long long>(c.pixels)
           << "</td><td>" << (c.is_board ? "<b>" : "") << svg::escape(c.verdict)
           << (c.is_board ? "</b>" : "") << "</td></tr>\n";
    }
    html << "</table>\n";
  }
  html << "</body></html>\n";
  const std::string page = (fs::path(dir) / "index.html").string();
  std::ofstream(page) << html.str();
  return page;
}

}  // namespace harmoloc::sim_host::colours
