#include "harmoloc/sim_host/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>

#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::sim_host {

namespace {

using Json = nlohmann::ordered_json;

constexpr double kRadToDeg = 180.0 / algorithms::kPi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// Small text helpers
// ---------------------------------------------------------------------------------------------

std::string format(const char* fmt, ...) __attribute__((format(printf, 1, 2)));

std::string format(const char* fmt, ...) {
  va_list args;
  va_start(args, fmt);
  va_list copy;
  va_copy(copy, args);
  char buffer[512];
  const int n = std::vsnprintf(buffer, sizeof buffer, fmt, args);
  va_end(args);
  std::string out;
  if (n > 0 && static_cast<std::size_t>(n) < sizeof buffer) {
    out.assign(buffer, static_cast<std::size_t>(n));
  } else if (n > 0) {
    out.resize(static_cast<std::size_t>(n) + 1);
    std::vsnprintf(out.data(), out.size(), fmt, copy);
    out.resize(static_cast<std::size_t>(n));
  }
  va_end(copy);
  return out;
}

/// Escapes text for XML/HTML content and attribute values.
std::string escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string cm(double metres) {
  return format("%.2f cm", metres * 100.0);
}

/// A duration in microseconds, in the unit that reads best ("812 us", "1.20 ms", "15.0 ms").
/// Plots and the page spell microseconds "µs" (@p micro_sign); the terminal gets plain "us".
std::string duration(double us, bool micro_sign = false) {
  const char* unit = micro_sign ? "µs" : "us";
  if (!std::isfinite(us)) return "n/a";
  if (us < 10.0) return format("%.1f %s", us, unit);
  if (us < 1000.0) return format("%.0f %s", us, unit);
  if (us < 10000.0) return format("%.2f ms", us / 1000.0);
  return format("%.1f ms", us / 1000.0);
}

/// A number for a table cell: "n/a" when it is NaN.
std::string cell(double value, int decimals) {
  if (!std::isfinite(value)) return "n/a";
  return format("%.*f", decimals, value);
}

/// The budget as configured ("15 ms", "12.5 ms").
std::string budget(double us) {
  return format("%g ms", us / 1000.0);
}

std::string seconds(double s) {
  return format("%g s", s);
}

// ---------------------------------------------------------------------------------------------
// Stats JSON helpers
// ---------------------------------------------------------------------------------------------

class StatsReader {
 public:
  explicit StatsReader(std::string origin) : origin_(std::move(origin)) {}

  [[noreturn]] void fail(const std::string& reason) const {
    throw ReportError(origin_ + ": " + reason);
  }

  std::optional<double> number(const Json& object, const std::string& key,
                               const std::string& where) const {
    const auto it = object.find(key);
    if (it == object.end() || it->is_null()) return std::nullopt;
    if (!it->is_number()) fail(where + key + " is not a number");
    return it->get<double>();
  }

  std::optional<std::uint64_t> count(const Json& value, const std::string& what) const {
    if (value.is_null()) return std::nullopt;
    if (value.is_number_unsigned()) return value.get<std::uint64_t>();
    if (value.is_number_integer()) {
      const auto v = value.get<std::int64_t>();
      if (v < 0) fail(what + " is negative");
      return static_cast<std::uint64_t>(v);
    }
    if (value.is_number_float()) {
      const double v = value.get<double>();
      if (v < 0.0 || v != std::floor(v) || v > 1.8e19) fail(what + " is not a count");
      return static_cast<std::uint64_t>(v);
    }
    fail(what + " is not a count");
  }

  std::optional<std::uint64_t> count(const Json& object, const std::string& key,
                                     const std::string& where) const {
    const auto it = object.find(key);
    if (it == object.end()) return std::nullopt;
    return count(*it, where + key);
  }

  std::string string(const Json& object, const std::string& key) const {
    const auto it = object.find(key);
    if (it == object.end() || it->is_null()) return "";
    if (!it->is_string()) fail(key + " is not a string");
    return it->get<std::string>();
  }

  /// The object at @p key, nullptr when missing; fails when present but not an object.
  const Json* object(const Json& parent, const std::string& key) const {
    const auto it = parent.find(key);
    if (it == parent.end() || it->is_null()) return nullptr;
    if (!it->is_object()) fail("\"" + key + "\" is not an object");
    return &*it;
  }

 private:
  std::string origin_;
};

std::string scalar_text(const Json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
  if (value.is_null()) return "null";
  if (value.is_number_unsigned()) return std::to_string(value.get<std::uint64_t>());
  if (value.is_number_integer()) return std::to_string(value.get<std::int64_t>());
  if (value.is_number_float()) return format("%.6g", value.get<double>());
  return value.dump();
}

void flatten(const Json& value, const std::string& prefix,
             std::vector<std::pair<std::string, std::string>>& out) {
  if (value.is_object()) {
    for (const auto& item : value.items()) {
      flatten(item.value(), prefix.empty() ? item.key() : prefix + "." + item.key(), out);
    }
    return;
  }
  if (value.is_array()) {
    bool scalars = value.size() <= 8;
    for (const auto& v : value) scalars = scalars && !v.is_structured();
    if (!scalars) {
      out.emplace_back(prefix, format("[%zu values]", value.size()));
      return;
    }
    std::string text = "[";
    for (std::size_t i = 0; i < value.size(); ++i) {
      if (i > 0) text += ", ";
      text += scalar_text(value[i]);
    }
    out.emplace_back(prefix, text + "]");
    return;
  }
  out.emplace_back(prefix, scalar_text(value));
}

// ---------------------------------------------------------------------------------------------
// SVG building blocks
// ---------------------------------------------------------------------------------------------

const char* const kFont = "DejaVu Sans, Helvetica, Arial, sans-serif";
const char* const kTruthColour = "#222222";
const char* const kEstimateColour = "#1f77b4";
const char* const kFixColour = "#ff7f0e";
const char* const kMedianColour = "#2ca02c";
const char* const kP99Colour = "#d62728";
const char* const kGridColour = "#e6e6e6";
const char* const kAxisColour = "#555555";
const char* const kTextColour = "#222222";
const char* const kMutedColour = "#666666";

/// Approximate rendered width of @p text at @p size px (DejaVu Sans averages ~0.6 em).
double text_width(const std::string& text, double size) {
  return 0.6 * size * static_cast<double>(text.size());
}

std::string num(double v) {
  if (std::fabs(v) < 0.05) v = 0.0;
  return format("%.1f", v);
}

class Svg {
 public:
  Svg(double width, double height) : width_(width), height_(height) {
    out_ << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
         << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(width) << "\" height=\""
         << num(height) << "\" viewBox=\"0 0 " << num(width) << ' ' << num(height)
         << "\" font-family=\"" << kFont << "\" font-size=\"12\">\n"
         << "<rect x=\"0\" y=\"0\" width=\"" << num(width) << "\" height=\"" << num(height)
         << "\" fill=\"#ffffff\"/>\n";
  }

  double width() const { return width_; }
  double height() const { return height_; }

  void raw(const std::string& text) { out_ << text; }

  void line(double x1, double y1, double x2, double y2, const char* stroke, double stroke_width,
            const std::string& extra = "") {
    out_ << "<line x1=\"" << num(x1) << "\" y1=\"" << num(y1) << "\" x2=\"" << num(x2) << "\" y2=\""
         << num(y2) << "\" stroke=\"" << stroke << "\" stroke-width=\""
         << format("%.2g", stroke_width) << '"' << extra << "/>\n";
  }

  void rect(double x, double y, double w, double h, const char* fill,
            const std::string& extra = "") {
    out_ << "<rect x=\"" << num(x) << "\" y=\"" << num(y) << "\" width=\"" << num(std::max(0.0, w))
         << "\" height=\"" << num(std::max(0.0, h)) << "\" fill=\"" << fill << '"' << extra
         << "/>\n";
  }

  void circle(double x, double y, double r, const char* fill, const std::string& extra = "") {
    out_ << "<circle cx=\"" << num(x) << "\" cy=\"" << num(y) << "\" r=\"" << format("%.2g", r)
         << "\" fill=\"" << fill << '"' << extra << "/>\n";
  }

  void text(double x, double y, const std::string& content, const char* anchor = "start",
            double size = 12.0, const char* fill = kTextColour, const std::string& extra = "") {
    out_ << "<text x=\"" << num(x) << "\" y=\"" << num(y) << "\" text-anchor=\"" << anchor
         << "\" font-size=\"" << format("%g", size) << "\" fill=\"" << fill << '"' << extra << '>'
         << escape(content) << "</text>\n";
  }

  void polyline(const std::vector<std::pair<double, double>>& points, const char* stroke,
                double stroke_width, const std::string& css_class, const std::string& extra = "") {
    out_ << "<polyline class=\"" << css_class << "\" fill=\"none\" stroke=\"" << stroke
         << "\" stroke-width=\"" << format("%.2g", stroke_width)
         << "\" stroke-linejoin=\"round\" stroke-linecap=\"round\"" << extra << " points=\"";
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (i > 0) out_ << ' ';
      out_ << num(points[i].first) << ',' << num(points[i].second);
    }
    out_ << "\"/>\n";
  }

  std::string finish() {
    out_ << "</svg>\n";
    return out_.str();
  }

 private:
  double width_;
  double height_;
  std::ostringstream out_;
};

/// Linear map of a value range onto a pixel range.
struct Scale {
  double v0 = 0.0;
  double v1 = 1.0;
  double p0 = 0.0;
  double p1 = 1.0;
  double operator()(double v) const { return p0 + (v - v0) * (p1 - p0) / (v1 - v0); }
};

struct Area {
  double left = 0.0;
  double top = 0.0;
  double width = 0.0;
  double height = 0.0;
  double right() const { return left + width; }
  double bottom() const { return top + height; }
};

/// A 1-2-5 step that gives about @p target intervals over @p range.
double nice_step(double range, int target) {
  if (!(range > 0.0) || !std::isfinite(range)) return 1.0;
  const double raw = range / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double norm = raw / magnitude;
  const double nice = norm < 1.5 ? 1.0 : norm < 3.0 ? 2.0 : norm < 7.0 ? 5.0 : 10.0;
  return nice * magnitude;
}

int decimals_for(double step) {
  const int d = static_cast<int>(-std::floor(std::log10(step) + 1e-9));
  return std::clamp(d, 0, 6);
}

/// Tick values that are multiples of @p step within [lo, hi].
std::vector<double> ticks_in(double lo, double hi, double step) {
  std::vector<double> out;
  const double first = std::ceil(lo / step - 1e-9) * step;
  for (double v = first; v <= hi + step * 1e-9 && out.size() < 200; v += step) {
    out.push_back(std::fabs(v) < step * 1e-9 ? 0.0 : v);
  }
  return out;
}

struct Tick {
  double px;
  std::string label;
};

std::vector<Tick> make_ticks(const Scale& scale, double step, double divisor = 1.0) {
  std::vector<Tick> out;
  const int decimals = decimals_for(step / divisor);
  for (const double v :
       ticks_in(std::min(scale.v0, scale.v1), std::max(scale.v0, scale.v1), step)) {
    out.push_back({scale(v), format("%.*f", decimals, v / divisor)});
  }
  return out;
}

/// Grid, frame, ticks, tick labels and axis titles of one plot area.
void draw_axes(Svg& svg, const Area& area, const std::vector<Tick>& x_ticks,
               const std::vector<Tick>& y_ticks, const std::string& x_title,
               const std::string& y_title, bool x_grid = true) {
  for (const Tick& t : y_ticks) {
    svg.line(area.left, t.px, area.right(), t.px, kGridColour, 1.0);
  }
  if (x_grid) {
    for (const Tick& t : x_ticks) {
      svg.line(t.px, area.top, t.px, area.bottom(), kGridColour, 1.0);
    }
  }
  svg.rect(area.left, area.top, area.width, area.height, "none",
           format(" stroke=\"%s\" stroke-width=\"1\"", kAxisColour));
  double widest = 0.0;
  for (const Tick& t : y_ticks) {
    svg.line(area.left - 5.0, t.px, area.left, t.px, kAxisColour, 1.0);
    svg.text(area.left - 8.0, t.px + 4.0, t.label, "end", 11.0);
    widest = std::max(widest, text_width(t.label, 11.0));
  }
  for (const Tick& t : x_ticks) {
    svg.line(t.px, area.bottom(), t.px, area.bottom() + 5.0, kAxisColour, 1.0);
    svg.text(t.px, area.bottom() + 18.0, t.label, "middle", 11.0);
  }
  if (!x_title.empty()) {
    svg.text(area.left + area.width / 2.0, area.bottom() + 38.0, x_title, "middle", 12.5);
  }
  if (!y_title.empty()) {
    const double x = area.left - widest - 18.0;
    const double y = area.top + area.height / 2.0;
    svg.text(x, y, y_title, "middle", 12.5, kTextColour,
             format(" transform=\"rotate(-90 %s %s)\"", num(x).c_str(), num(y).c_str()));
  }
}

struct LegendItem {
  enum class Kind { kLine, kDashedLine, kDot, kRing, kBox };
  Kind kind;
  const char* colour;
  std::string label;
};

/// One row of legend entries starting at (x, y) (y = text baseline). Returns the row's width.
double draw_legend(Svg& svg, double x, double y, const std::vector<LegendItem>& items,
                   bool draw = true) {
  double cursor = x;
  for (const LegendItem& item : items) {
    if (draw) {
      const double cy = y - 4.0;
      switch (item.kind) {
        case LegendItem::Kind::kLine:
          svg.line(cursor, cy, cursor + 22, cy, item.colour, 2.5);
          break;
        case LegendItem::Kind::kDashedLine:
          svg.line(cursor, cy, cursor + 22, cy, item.colour, 2.0, " stroke-dasharray=\"5,3\"");
          break;
        case LegendItem::Kind::kDot:
          svg.circle(cursor + 11, cy, 3.0, item.colour);
          break;
        case LegendItem::Kind::kRing:
          svg.circle(cursor + 11, cy, 5.0, "none",
                     format(" stroke=\"%s\" stroke-width=\"2\"", item.colour));
          break;
        case LegendItem::Kind::kBox:
          svg.rect(cursor + 4, cy - 6, 14, 12, item.colour);
          break;
      }
      svg.text(cursor + 28, y, item.label, "start", 12.0);
    }
    cursor += 28 + text_width(item.label, 12.0) + 20;
  }
  return cursor - x - 20;
}

std::string clip_path(const std::string& id, const Area& area) {
  return format(
      "<defs><clipPath id=\"%s\"><rect x=\"%s\" y=\"%s\" width=\"%s\" "
      "height=\"%s\"/></clipPath></defs>\n",
      id.c_str(), num(area.left).c_str(), num(area.top).c_str(), num(area.width).c_str(),
      num(area.height).c_str());
}

/// Centred caption lines under a plot, 15 px apart, first baseline at @p y.
void draw_caption(Svg& svg, double y, const std::vector<std::string>& lines) {
  for (std::size_t i = 0; i < lines.size(); ++i) {
    svg.text(svg.width() / 2.0, y + 15.0 * static_cast<double>(i), lines[i], "middle", 11.5,
             kMutedColour);
  }
}

struct Box {
  double x0 = kInf, y0 = kInf, x1 = -kInf, y1 = -kInf;
  bool empty() const { return !(x1 >= x0); }
  void add(double x, double y) {
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
  bool contains(double x, double y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
};

void write_file(const std::filesystem::path& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
  out << content;
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Evaluation
// ---------------------------------------------------------------------------------------------

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(rank));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = rank - static_cast<double>(lo);
  return values[lo] + frac * (values[hi] - values[lo]);
}

TrajectoryErrors evaluate(const std::vector<dataset::StampedPose>& truth,
                          const std::vector<dataset::StampedPose>& estimate,
                          const EvaluateOptions& options) {
  TrajectoryErrors out;
  out.skip_initial_s = options.skip_initial_s;
  if (truth.empty()) {
    out.outside_truth = estimate.size();
    return out;
  }
  const double from_s = truth.front().t_s + options.skip_initial_s;
  double sum_x2 = 0.0, sum_y2 = 0.0, sum_h2 = 0.0, sum_p = 0.0;
  std::vector<double> positions;
  for (const dataset::StampedPose& e : estimate) {
    algorithms::Pose2 reference;
    if (!dataset::interpolate(truth, e.t_s, reference)) {
      ++out.outside_truth;
      continue;
    }
    if (e.t_s < from_s) {
      ++out.skipped;
      continue;
    }
    ErrorSample s;
    s.t_s = e.t_s;
    s.dx_m = e.pose.x_m - reference.x_m;
    s.dy_m = e.pose.y_m - reference.y_m;
    s.position_m = std::hypot(s.dx_m, s.dy_m);
    s.heading_rad = algorithms::wrap_angle_rad(e.pose.yaw_rad - reference.yaw_rad);
    sum_x2 += s.dx_m * s.dx_m;
    sum_y2 += s.dy_m * s.dy_m;
    sum_h2 += s.heading_rad * s.heading_rad;
    sum_p += s.position_m;
    out.max_position_m = std::max(out.max_position_m, s.position_m);
    out.max_heading_deg = std::max(out.max_heading_deg, std::fabs(s.heading_rad) * kRadToDeg);
    positions.push_back(s.position_m);
    out.samples.push_back(s);
  }
  out.count = out.samples.size();
  if (out.count == 0) return out;
  const double n = static_cast<double>(out.count);
  const double mse_x = sum_x2 / n;
  const double mse_y = sum_y2 / n;
  out.rmse_x_m = std::sqrt(mse_x);
  out.rmse_y_m = std::sqrt(mse_y);
  out.rmse_position_m = std::sqrt(mse_x + mse_y);
  out.mse_x_cm2 = mse_x * 1e4;
  out.mse_y_cm2 = mse_y * 1e4;
  out.mean_position_m = sum_p / n;
  out.rmse_heading_deg = std::sqrt(sum_h2 / n) * kRadToDeg;
  out.p95_position_m = percentile(std::move(positions), 95.0);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Stats
// ---------------------------------------------------------------------------------------------

const char* const kStageOrder[8] = {"acquire", "segment", "localize", "encoders",
                                    "predict", "update",  "publish",  "cycle"};

std::uint64_t CycleHistogram::overflow() const {
  return counts.size() > upper_us.size() ? counts.back() : 0;
}

std::uint64_t CycleHistogram::total() const {
  std::uint64_t sum = 0;
  for (const std::uint64_t c : counts) sum += c;
  return sum;
}

const StageTiming* RunStats::stage(const std::string& name) const {
  for (const StageTiming& s : stages) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

RunStats parse_stats(const std::string& text, const std::string& origin) {
  const StatsReader reader(origin);
  Json doc;
  try {
    doc = Json::parse(text);
  } catch (const Json::exception& e) {
    std::string what = e.what();
    const auto bracket = what.find("] ");
    if (what.rfind("[json.exception", 0) == 0 && bracket != std::string::npos) {
      what = what.substr(bracket + 2);
    }
    reader.fail("not valid JSON (" + what + ")");
  }
  if (!doc.is_object()) reader.fail("not a JSON object");

  RunStats stats;
  stats.harmoloc_version = reader.string(doc, "harmoloc_version");
  stats.board = reader.string(doc, "board");
  stats.cycles = reader.count(doc, "cycles", "");
  stats.frames = reader.count(doc, "frames", "");
  stats.overruns = reader.count(doc, "overruns", "");
  stats.rate_hz = reader.number(doc, "rate_hz", "");
  if (const auto budget = reader.number(doc, "budget_us", "")) {
    if (!(*budget > 0.0)) reader.fail("budget_us must be positive");
    stats.budget_us = *budget;
  }

  const Json* stages = reader.object(doc, "stages");
  if (stages == nullptr) reader.fail("no \"stages\" section (is this a harmoloc --stats file?)");
  // Known stages in display order, then unknown ones in file order, the whole cycle last.
  std::vector<std::string> names(std::begin(kStageOrder), std::end(kStageOrder) - 1);
  for (const auto& item : stages->items()) {
    if (std::find(std::begin(kStageOrder), std::end(kStageOrder), item.key()) ==
        std::end(kStageOrder)) {
      names.push_back(item.key());
    }
  }
  names.push_back("cycle");
  for (const std::string& name : names) {
    const auto it = stages->find(name);
    if (it == stages->end()) continue;
    if (!it->is_object()) reader.fail("stages." + name + " is not an object");
    const std::string where = "stages." + name + ".";
    StageTiming s;
    s.name = name;
    s.median_us = reader.number(*it, "median_us", where).value_or(kNaN);
    s.p99_us = reader.number(*it, "p99_us", where).value_or(kNaN);
    s.p999_us = reader.number(*it, "p999_us", where).value_or(kNaN);
    s.max_us = reader.number(*it, "max_us", where).value_or(kNaN);
    s.mean_us = reader.number(*it, "mean_us", where).value_or(kNaN);
    stats.stages.push_back(s);
  }

  if (const Json* histogram = reader.object(doc, "cycle_histogram")) {
    const auto upper = histogram->find("upper_us");
    const auto counts = histogram->find("counts");
    if (upper == histogram->end() || !upper->is_array() || counts == histogram->end() ||
        !counts->is_array()) {
      reader.fail("cycle_histogram needs the arrays \"upper_us\" and \"counts\"");
    }
    CycleHistogram h;
    for (const Json& v : *upper) {
      if (!v.is_number()) reader.fail("cycle_histogram.upper_us holds a non-number");
      const double bound = v.get<double>();
      if (!(bound > 0.0) || (!h.upper_us.empty() && !(bound > h.upper_us.back()))) {
        reader.fail("cycle_histogram.upper_us must be positive and increasing");
      }
      h.upper_us.push_back(bound);
    }
    for (const Json& v : *counts) {
      h.counts.push_back(reader.count(v, "a cycle_histogram count").value_or(0));
    }
    if (h.counts.size() != h.upper_us.size() && h.counts.size() != h.upper_us.size() + 1) {
      reader.fail(format("cycle_histogram has %zu counts for %zu buckets", h.counts.size(),
                         h.upper_us.size()));
    }
    if (!h.upper_us.empty()) stats.cycle_histogram = std::move(h);
  }

  if (const Json* degraded = reader.object(doc, "degraded")) {
    for (const auto& item : degraded->items()) {
      if (const auto c = reader.count(item.value(), "degraded." + item.key())) {
        stats.degraded.emplace_back(item.key(), *c);
      }
    }
  }
  if (const Json* localizer = reader.object(doc, "localizer")) {
    stats.localizer_fixes = reader.count(*localizer, "fixes", "localizer.");
    stats.localizer_unknown_place = reader.count(*localizer, "unknown_place", "localizer.");
  }
  for (const auto& item : doc.items()) {
    if (!item.value().is_object() || item.key() == "stages" || item.key() == "cycle_histogram" ||
        item.key() == "degraded") {
      continue;
    }
    StatsSection section;
    section.name = item.key();
    flatten(item.value(), "", section.entries);
    stats.sections.push_back(std::move(section));
  }
  return stats;
}

RunStats read_stats(const std::string& path) {
  std::string text;
  if (const std::string e =
          drivers::read_regular_file(path, drivers::input_limits::kStatsBytes, text);
      !e.empty()) {
    throw ReportError(path + ": " + e);
  }
  return parse_stats(text, path);
}

// ---------------------------------------------------------------------------------------------
// Building the report
// ---------------------------------------------------------------------------------------------

Report build_report(ReportInputs inputs, std::vector<dataset::StampedPose> truth,
                    std::vector<dataset::StampedPose> estimate,
                    std::vector<dataset::StampedPose> fixes, std::optional<RunStats> stats) {
  const std::string truth_name = inputs.truth_path.empty() ? "truth" : inputs.truth_path;
  const std::string estimate_name =
      inputs.estimate_path.empty() ? "estimate" : inputs.estimate_path;
  const std::string fixes_name = inputs.fixes_path.empty() ? "fixes" : inputs.fixes_path;
  if (truth.size() < 2) {
    throw ReportError(format("%s: ground truth needs at least two poses (has %zu)",
                             truth_name.c_str(), truth.size()));
  }
  if (estimate.empty()) throw ReportError(estimate_name + ": no poses");
  if (!std::isfinite(inputs.skip_initial_s) || inputs.skip_initial_s < 0.0) {
    throw ReportError("the initial skip must be a non-negative number of seconds");
  }
  const bool with_fixes = !inputs.fixes_path.empty() || !fixes.empty();
  if (with_fixes && fixes.empty()) throw ReportError(fixes_name + ": no poses");

  const auto span_error = [&](const std::string& name,
                              const std::vector<dataset::StampedPose>& poses) {
    return ReportError(
        format("%s: no pose lies within the ground truth's time span (truth "
               "%.3f..%.3f s, %s %.3f..%.3f s)",
               name.c_str(), truth.front().t_s, truth.back().t_s,
               name == fixes_name ? "fixes" : "estimate", poses.front().t_s, poses.back().t_s));
  };
  const double skip = inputs.skip_initial_s;

  Report report;
  report.estimate_all = evaluate(truth, estimate);
  if (report.estimate_all.count == 0) throw span_error(estimate_name, estimate);
  if (skip > 0.0) {
    report.estimate_converged = evaluate(truth, estimate, {skip});
    if (report.estimate_converged->count == 0) {
      throw ReportError(
          format("%s: skipping the first %g s leaves no pose to score (the ground "
                 "truth lasts %.3f s)",
                 estimate_name.c_str(), skip, truth.back().t_s - truth.front().t_s));
    }
  }
  if (with_fixes) {
    report.fixes_all = evaluate(truth, fixes);
    if (report.fixes_all->count == 0) throw span_error(fixes_name, fixes);
    if (skip > 0.0) {
      TrajectoryErrors converged = evaluate(truth, fixes, {skip});
      if (converged.count > 0) report.fixes_converged = std::move(converged);
    }
  }
  report.inputs = std::move(inputs);
  report.truth = std::move(truth);
  report.estimate = std::move(estimate);
  report.fixes = std::move(fixes);
  report.stats = std::move(stats);
  return report;
}

Report load_report(const ReportInputs& inputs) {
  for (const std::string* path :
       {&inputs.truth_path, &inputs.estimate_path, &inputs.fixes_path, &inputs.stats_path}) {
    std::error_code ec;
    if (!path->empty() && std::filesystem::is_directory(*path, ec)) {
      throw ReportError(*path + ": is a directory, expected a file");
    }
  }
  std::vector<dataset::StampedPose> truth = dataset::read_tum(inputs.truth_path);
  std::vector<dataset::StampedPose> estimate = dataset::read_tum(inputs.estimate_path);
  std::vector<dataset::StampedPose> fixes;
  if (!inputs.fixes_path.empty()) fixes = dataset::read_tum(inputs.fixes_path);
  std::optional<RunStats> stats;
  if (!inputs.stats_path.empty()) stats = read_stats(inputs.stats_path);
  return build_report(inputs, std::move(truth), std::move(estimate), std::move(fixes),
                      std::move(stats));
}

// ---------------------------------------------------------------------------------------------
// Text and JSON summaries
// ---------------------------------------------------------------------------------------------

namespace {

std::string position_line(const TrajectoryErrors& e) {
  return format("x %s  y %s  xy %s  (max %s, p95 %s)", cm(e.rmse_x_m).c_str(),
                cm(e.rmse_y_m).c_str(), cm(e.rmse_position_m).c_str(), cm(e.max_position_m).c_str(),
                cm(e.p95_position_m).c_str());
}

std::string fixes_line(const TrajectoryErrors& e) {
  return format("RMSE %s (x %.2f, y %.2f; MSE x %.1f, y %.1f cm2) over %zu fixes",
                cm(e.rmse_position_m).c_str(), e.rmse_x_m * 100.0, e.rmse_y_m * 100.0, e.mse_x_cm2,
                e.mse_y_cm2, e.count);
}

Json errors_json(const TrajectoryErrors& e, bool heading) {
  Json j;
  j["count"] = e.count;
  j["outside_truth"] = e.outside_truth;
  j["skipped"] = e.skipped;
  j["skip_initial_s"] = e.skip_initial_s;
  j["rmse_x_cm"] = e.rmse_x_m * 100.0;
  j["rmse_y_cm"] = e.rmse_y_m * 100.0;
  j["rmse_position_cm"] = e.rmse_position_m * 100.0;
  j["mse_x_cm2"] = e.mse_x_cm2;
  j["mse_y_cm2"] = e.mse_y_cm2;
  j["mean_position_cm"] = e.mean_position_m * 100.0;
  j["p95_position_cm"] = e.p95_position_m * 100.0;
  j["max_position_cm"] = e.max_position_m * 100.0;
  if (heading) {
    j["rmse_heading_deg"] = e.rmse_heading_deg;
    j["max_heading_deg"] = e.max_heading_deg;
  }
  return j;
}

Json number_or_null(double v) {
  return std::isfinite(v) ? Json(v) : Json(nullptr);
}

/// The budget share of the cycle's p99, NaN when unknown.
double p99_budget_percent(const RunStats& stats) {
  const StageTiming* cycle = stats.stage("cycle");
  if (cycle == nullptr) return kNaN;
  return cycle->p99_us / stats.budget_us * 100.0;
}

}  // namespace

std::string summary_text(const Report& report, const std::string& index_path) {
  std::string out;
  if (!report.inputs.title.empty()) out += "harmoloc run report: " + report.inputs.title + "\n";
  const TrajectoryErrors& all = report.estimate_all;
  const TrajectoryErrors* late = report.estimate_converged ? &*report.estimate_converged : nullptr;
  const std::string after = format("  after %-7s", seconds(report.inputs.skip_initial_s).c_str());
  out += format("position RMSE  %s over %zu poses", position_line(all).c_str(), all.count);
  if (all.outside_truth > 0) {
    out += format(" (%zu more outside the truth's time span)", all.outside_truth);
  }
  out += "\n";
  if (late != nullptr) {
    out +=
        format("%s%s over %zu poses\n", after.c_str(), position_line(*late).c_str(), late->count);
  }
  out += format("position MSE   x %.2f cm2  y %.2f cm2\n", all.mse_x_cm2, all.mse_y_cm2);
  if (late != nullptr) {
    out += format("%sx %.2f cm2  y %.2f cm2\n", after.c_str(), late->mse_x_cm2, late->mse_y_cm2);
  }
  out += format("heading RMSE   %.2f deg  (max %.1f deg)\n", all.rmse_heading_deg,
                all.max_heading_deg);
  if (late != nullptr) {
    out += format("%s%.2f deg  (max %.1f deg)\n", after.c_str(), late->rmse_heading_deg,
                  late->max_heading_deg);
  }
  if (report.fixes_all) {
    out += "harmonic fixes " + fixes_line(*report.fixes_all) + "\n";
  }
  if (report.fixes_converged) {
    out += after + fixes_line(*report.fixes_converged) + "\n";
  }
  if (report.stats) {
    const RunStats& stats = *report.stats;
    const std::string overruns =
        stats.overruns ? std::to_string(*stats.overruns) : std::string("n/a");
    if (const StageTiming* cycle = stats.stage("cycle")) {
      out += format(
          "cycle time     median %s  p99 %s  max %s  (budget %s, %.1f%% used at p99), "
          "overruns %s\n",
          duration(cycle->median_us).c_str(), duration(cycle->p99_us).c_str(),
          duration(cycle->max_us).c_str(), budget(stats.budget_us).c_str(),
          p99_budget_percent(stats), overruns.c_str());
    } else {
      out += format("cycle time     n/a (no \"cycle\" stage)  budget %s, overruns %s\n",
                    budget(stats.budget_us).c_str(), overruns.c_str());
    }
    const StageTiming* slowest = nullptr;
    for (const StageTiming& s : stats.stages) {
      if (s.name == "cycle" || !std::isfinite(s.p99_us)) continue;
      if (slowest == nullptr || s.p99_us > slowest->p99_us) slowest = &s;
    }
    if (!stats.stages.empty()) {
      out +=
          format("per stage      %-10s %10s %10s %10s %10s\n", "", "median", "p99", "p99.9", "max");
      for (const StageTiming& s : stats.stages) {
        out += format("               %-10s %10s %10s %10s %10s\n", s.name.c_str(),
                      duration(s.median_us).c_str(), duration(s.p99_us).c_str(),
                      duration(s.p999_us).c_str(), duration(s.max_us).c_str());
      }
    }
    if (slowest != nullptr) {
      out += format("slowest stage  %s (median %s, p99 %s)\n", slowest->name.c_str(),
                    duration(slowest->median_us).c_str(), duration(slowest->p99_us).c_str());
    }
    if (!stats.degraded.empty()) {
      std::string list;
      for (const auto& [name, count] : stats.degraded) {
        if (!list.empty()) list += ", ";
        list += name + " " + std::to_string(count);
      }
      if (stats.cycles)
        list += format(" (of %llu cycles)", static_cast<unsigned long long>(*stats.cycles));
      out += "degraded       " + list + "\n";
    }
  }
  if (!index_path.empty()) out += "report         " + index_path + "\n";
  return out;
}

std::string summary_json(const Report& report) {
  Json j;
  j["title"] = report.inputs.title;
  j["inputs"] = {
      {"truth", report.inputs.truth_path},
      {"estimate", report.inputs.estimate_path},
      {"fixes", report.inputs.fixes_path.empty() ? Json(nullptr) : Json(report.inputs.fixes_path)},
      {"stats", report.inputs.stats_path.empty() ? Json(nullptr) : Json(report.inputs.stats_path)}};
  j["skip_initial_s"] = report.inputs.skip_initial_s;
  j["units"] = "lengths in cm, MSE in cm2, angles in degrees, times in microseconds";
  Json estimate;
  estimate["all"] = errors_json(report.estimate_all, true);
  if (report.estimate_converged) {
    estimate["after_convergence"] = errors_json(*report.estimate_converged, true);
  }
  j["estimate"] = estimate;
  if (report.fixes_all) {
    Json fixes;
    fixes["all"] = errors_json(*report.fixes_all, false);
    if (report.fixes_converged) {
      fixes["after_convergence"] = errors_json(*report.fixes_converged, false);
    }
    j["fixes"] = fixes;
  }
  if (report.stats) {
    const RunStats& s = *report.stats;
    Json timing;
    timing["harmoloc_version"] = s.harmoloc_version;
    timing["board"] = s.board;
    timing["budget_us"] = s.budget_us;
    timing["cycles"] = s.cycles ? Json(*s.cycles) : Json(nullptr);
    timing["frames"] = s.frames ? Json(*s.frames) : Json(nullptr);
    timing["overruns"] = s.overruns ? Json(*s.overruns) : Json(nullptr);
    timing["rate_hz"] = s.rate_hz ? Json(*s.rate_hz) : Json(nullptr);
    timing["cycle_p99_budget_percent"] = number_or_null(p99_budget_percent(s));
    Json stages = Json::object();
    for (const StageTiming& st : s.stages) {
      stages[st.name] = {{"median_us", number_or_null(st.median_us)},
                         {"p99_us", number_or_null(st.p99_us)},
                         {"p999_us", number_or_null(st.p999_us)},
                         {"max_us", number_or_null(st.max_us)},
                         {"mean_us", number_or_null(st.mean_us)}};
    }
    timing["stages"] = stages;
    Json degraded = Json::object();
    for (const auto& [name, count] : s.degraded) degraded[name] = count;
    timing["degraded"] = degraded;
    if (s.localizer_fixes || s.localizer_unknown_place) {
      timing["localizer"] = {
          {"fixes", s.localizer_fixes ? Json(*s.localizer_fixes) : Json(nullptr)},
          {"unknown_place",
           s.localizer_unknown_place ? Json(*s.localizer_unknown_place) : Json(nullptr)}};
    }
    j["timing"] = timing;
  }
  return j.dump(2) + "\n";
}

// ---------------------------------------------------------------------------------------------
// Plots
// ---------------------------------------------------------------------------------------------

std::string trajectory_svg(const Report& report) {
  // The view: the truth's box, grown to take in the estimate and fixes unless they run far
  // away (then they are clipped and counted, so that one wild fix does not shrink the route).
  Box truth_box;
  for (const dataset::StampedPose& p : report.truth) truth_box.add(p.pose.x_m, p.pose.y_m);
  const double extent = std::max({truth_box.width(), truth_box.height(), 0.2});
  Box limit = truth_box;
  const double grow = 0.5 * extent + 0.5;
  limit.x0 -= grow;
  limit.y0 -= grow;
  limit.x1 += grow;
  limit.y1 += grow;
  Box view = truth_box;
  std::size_t outside = 0;
  const auto take = [&](const std::vector<dataset::StampedPose>& poses) {
    for (const dataset::StampedPose& p : poses) {
      if (limit.contains(p.pose.x_m, p.pose.y_m)) {
        view.add(p.pose.x_m, p.pose.y_m);
      } else {
        ++outside;
      }
    }
  };
  take(report.estimate);
  take(report.fixes);
  // Padding, and a minimum extent on the short side so that a straight run is not a sliver.
  double span = std::max({view.width(), view.height(), 0.2});
  const double pad = 0.04 * span;
  view.x0 -= pad;
  view.x1 += pad;
  view.y0 -= pad;
  view.y1 += pad;
  span = std::max(view.width(), view.height());
  const double min_side = 0.3 * span;
  if (view.width() < min_side) {
    const double c = 0.5 * (view.x0 + view.x1);
    view.x0 = c - 0.5 * min_side;
    view.x1 = c + 0.5 * min_side;
  }
  if (view.height() < min_side) {
    const double c = 0.5 * (view.y0 + view.y1);
    view.y0 = c - 0.5 * min_side;
    view.y1 = c + 0.5 * min_side;
  }
  const double step = nice_step(span, 8);
  view.x0 = std::floor(view.x0 / step - 1e-9) * step;
  view.y0 = std::floor(view.y0 / step - 1e-9) * step;
  view.x1 = std::ceil(view.x1 / step + 1e-9) * step;
  view.y1 = std::ceil(view.y1 / step + 1e-9) * step;

  const double max_w = 760.0, max_h = 560.0;
  const double scale = std::min(max_w / view.width(), max_h / view.height());
  const double plot_w = view.width() * scale;
  const double plot_h = view.height() * scale;
  std::vector<std::string> caption = {
      format("equal aspect, grid %g m;  %zu truth poses, %zu estimate poses", step,
             report.truth.size(), report.estimate.size())};
  if (!report.fixes.empty()) caption[0] += format(", %zu fixes", report.fixes.size());
  if (outside > 0) {
    caption.push_back(format("%zu point%s far off the route %s outside the view", outside,
                             outside == 1 ? "" : "s", outside == 1 ? "is" : "are"));
  }
  const double left_margin = 80.0, right_margin = 30.0, top = 84.0;
  const double bottom_margin = 66.0 + 15.0 * static_cast<double>(caption.size());
  const double canvas_w = std::max(640.0, plot_w + left_margin + right_margin);
  const double left = left_margin + (canvas_w - (plot_w + left_margin + right_margin)) / 2.0;
  const Area area{left, top, plot_w, plot_h};
  Svg svg(canvas_w, top + plot_h + bottom_margin);

  const Scale sx{view.x0, view.x1, area.left, area.right()};
  const Scale sy{view.y0, view.y1, area.bottom(), area.top};  // y up

  svg.text(canvas_w / 2.0, 26.0, "Trajectory: ground truth vs fused estimate", "middle", 17.0,
           kTextColour, " font-weight=\"bold\"");
  std::vector<LegendItem> legend = {
      {LegendItem::Kind::kLine, kTruthColour, "ground truth"},
      {LegendItem::Kind::kLine, kEstimateColour, "fused estimate"},
  };
  if (!report.fixes.empty()) {
    legend.push_back({LegendItem::Kind::kDot, kFixColour, "harmonic fixes"});
  }
  legend.push_back({LegendItem::Kind::kRing, "#2ca02c", "start"});
  const double legend_w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, (canvas_w - legend_w) / 2.0, 56.0, legend);

  draw_axes(svg, area, make_ticks(sx, step), make_ticks(sy, step), "x (m)", "y (m)");

  svg.raw(clip_path("trajectory-plot", area));
  svg.raw("<g clip-path=\"url(#trajectory-plot)\">\n");
  if (!report.fixes.empty()) {
    svg.raw(format("<g class=\"fixes\" fill=\"%s\" fill-opacity=\"0.55\">\n", kFixColour));
    for (const dataset::StampedPose& p : report.fixes) {
      svg.raw(format("<circle cx=\"%s\" cy=\"%s\" r=\"1.8\"/>\n", num(sx(p.pose.x_m)).c_str(),
                     num(sy(p.pose.y_m)).c_str()));
    }
    svg.raw("</g>\n");
  }
  std::vector<std::pair<double, double>> points;
  for (const dataset::StampedPose& p : report.truth)
    points.emplace_back(sx(p.pose.x_m), sy(p.pose.y_m));
  svg.polyline(points, kTruthColour, 2.4, "truth", " stroke-opacity=\"0.85\"");
  points.clear();
  for (const dataset::StampedPose& p : report.estimate) {
    points.emplace_back(sx(p.pose.x_m), sy(p.pose.y_m));
  }
  svg.polyline(points, kEstimateColour, 1.5, "estimate");
  const dataset::StampedPose& start = report.truth.front();
  svg.circle(sx(start.pose.x_m), sy(start.pose.y_m), 6.0, "none",
             " stroke=\"#2ca02c\" stroke-width=\"2.5\"");
  svg.raw("</g>\n");

  draw_caption(svg, area.bottom() + 64.0, caption);
  return svg.finish();
}

std::string error_svg(const Report& report) {
  const double t0 = report.truth.front().t_s;
  const double duration_s = std::max(report.truth.back().t_s - t0, 1e-3);
  const TrajectoryErrors& est = report.estimate_all;
  const std::optional<TrajectoryErrors>& fixes = report.fixes_all;

  const double width = 860.0;
  const double left = 80.0, right = 30.0;
  const Area top_area{left, 84.0, width - left - right, 250.0};
  const Area bottom_area{left, top_area.bottom() + 56.0, width - left - right, 170.0};
  const double skip = report.inputs.skip_initial_s;
  std::vector<std::string> caption = {format("fused estimate: %zu poses, RMSE %s, max %s",
                                             est.count, cm(est.rmse_position_m).c_str(),
                                             cm(est.max_position_m).c_str())};
  if (est.outside_truth > 0) {
    caption[0] +=
        format(";  %zu poses outside the ground truth's time span not scored", est.outside_truth);
  }
  if (skip > 0.0) {
    caption.push_back(
        format("the first %g s (shaded) are left out of the \"after\" numbers", skip));
  }
  if (fixes) caption.push_back("");  // filled in once the panel's range is known
  Svg svg(width, bottom_area.bottom() + 62.0 + 15.0 * static_cast<double>(caption.size()));

  svg.text(width / 2.0, 26.0, "Error against ground truth over time", "middle", 17.0, kTextColour,
           " font-weight=\"bold\"");
  std::vector<LegendItem> legend = {
      {LegendItem::Kind::kLine, kEstimateColour, "fused estimate"},
      {LegendItem::Kind::kDashedLine, kEstimateColour, "fused RMSE " + cm(est.rmse_position_m)}};
  if (fixes) legend.push_back({LegendItem::Kind::kDot, kFixColour, "harmonic fixes"});
  if (report.inputs.skip_initial_s > 0.0) {
    legend.push_back({LegendItem::Kind::kBox, "#eeeeee", "excluded (convergence)"});
  }
  const double legend_w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, (width - legend_w) / 2.0, 56.0, legend);

  const double x_step = nice_step(duration_s, 10);
  const Scale sx_top{0.0, duration_s, top_area.left, top_area.right()};
  const Scale sx_bottom{0.0, duration_s, bottom_area.left, bottom_area.right()};

  // Position panel. A few wild fixes must not flatten the fused curve: the panel reaches the
  // fixes' p99 and clips the rest (counted in the caption).
  double y_max_cm = est.max_position_m * 100.0;
  std::size_t fixes_above = 0;
  if (fixes) {
    std::vector<double> e;
    for (const ErrorSample& s : fixes->samples) e.push_back(s.position_m * 100.0);
    y_max_cm = std::max(y_max_cm, percentile(e, 99.0));
  }
  y_max_cm = std::max(y_max_cm, 0.1);
  const double y_step = nice_step(y_max_cm * 1.05, 5);
  y_max_cm = std::ceil(y_max_cm * 1.05 / y_step - 1e-9) * y_step;
  const Scale sy_top{0.0, y_max_cm, top_area.bottom(), top_area.top};
  if (fixes) {
    for (const ErrorSample& s : fixes->samples) fixes_above += s.position_m * 100.0 > y_max_cm;
  }

  const auto shade_skip = [&](const Area& area, const Scale& sx) {
    if (skip <= 0.0) return;
    svg.rect(area.left, area.top, std::min(sx(skip), area.right()) - area.left, area.height,
             "#eeeeee");
  };
  shade_skip(top_area, sx_top);
  draw_axes(svg, top_area, make_ticks(sx_top, x_step), make_ticks(sy_top, y_step), "",
            "position error (cm)");
  svg.text(top_area.left + 6.0, top_area.top - 8.0, "position error", "start", 13.0, kTextColour,
           " font-weight=\"bold\"");

  svg.raw(clip_path("error-top", top_area));
  svg.raw("<g clip-path=\"url(#error-top)\">\n");
  if (fixes) {
    svg.raw(format("<g class=\"fixes\" fill=\"%s\" fill-opacity=\"0.5\">\n", kFixColour));
    for (const ErrorSample& s : fixes->samples) {
      svg.raw(format("<circle cx=\"%s\" cy=\"%s\" r=\"1.4\"/>\n", num(sx_top(s.t_s - t0)).c_str(),
                     num(sy_top(s.position_m * 100.0)).c_str()));
    }
    svg.raw("</g>\n");
  }
  std::vector<std::pair<double, double>> points;
  for (const ErrorSample& s : est.samples) {
    points.emplace_back(sx_top(s.t_s - t0), sy_top(s.position_m * 100.0));
  }
  svg.polyline(points, kEstimateColour, 1.4, "position-error");
  const double rmse_y = sy_top(est.rmse_position_m * 100.0);
  svg.line(top_area.left, rmse_y, top_area.right(), rmse_y, kEstimateColour, 1.2,
           " stroke-dasharray=\"6,4\"");
  svg.raw("</g>\n");

  // Heading panel: signed error, symmetric axis.
  const double h_max = std::max(est.max_heading_deg, 0.5);
  const double h_step = nice_step(2.0 * h_max * 1.05, 4);
  const double h_lim = std::ceil(h_max * 1.05 / h_step - 1e-9) * h_step;
  const Scale sy_bottom{-h_lim, h_lim, bottom_area.bottom(), bottom_area.top};
  shade_skip(bottom_area, sx_bottom);
  draw_axes(svg, bottom_area, make_ticks(sx_bottom, x_step), make_ticks(sy_bottom, h_step),
            "time since start of ground truth (s)", "heading error (deg)");
  svg.text(bottom_area.left + 6.0, bottom_area.top - 8.0,
           format("heading error (estimate - truth), RMSE %.2f deg", est.rmse_heading_deg), "start",
           13.0, kTextColour, " font-weight=\"bold\"");
  svg.line(bottom_area.left, sy_bottom(0.0), bottom_area.right(), sy_bottom(0.0), kAxisColour, 1.0);
  points.clear();
  for (const ErrorSample& s : est.samples) {
    points.emplace_back(sx_bottom(s.t_s - t0), sy_bottom(s.heading_rad * kRadToDeg));
  }
  svg.raw(clip_path("error-bottom", bottom_area));
  svg.raw("<g clip-path=\"url(#error-bottom)\">\n");
  svg.polyline(points, kEstimateColour, 1.4, "heading-error");
  svg.raw("</g>\n");

  if (fixes) {
    caption.back() =
        format("harmonic fixes: %zu, RMSE %s", fixes->count, cm(fixes->rmse_position_m).c_str());
    if (fixes_above > 0) {
      caption.back() +=
          format(";  %zu above the panel (max %s)", fixes_above, cm(fixes->max_position_m).c_str());
    }
  }
  draw_caption(svg, bottom_area.bottom() + 62.0, caption);
  return svg.finish();
}

std::string timing_svg(const RunStats& stats) {
  const double width = 860.0;
  const Area area{80.0, 100.0, width - 80.0 - 30.0, 260.0};
  Svg svg(width, area.bottom() + 90.0);
  const StageTiming* cycle = stats.stage("cycle");
  const std::uint64_t total = stats.cycle_histogram ? stats.cycle_histogram->total() : 0;
  svg.text(width / 2.0, 26.0,
           format("Whole-cycle compute time (%llu cycles)", static_cast<unsigned long long>(total)),
           "middle", 17.0, kTextColour, " font-weight=\"bold\"");
  std::string subtitle = "budget " + budget(stats.budget_us) + " per cycle";
  if (cycle != nullptr && std::isfinite(cycle->p99_us)) {
    subtitle +=
        format(": p99 uses %.1f%% of it, max %.1f%%", cycle->p99_us / stats.budget_us * 100.0,
               cycle->max_us / stats.budget_us * 100.0);
  }
  if (stats.overruns) {
    subtitle += format(";  %llu overrun%s", static_cast<unsigned long long>(*stats.overruns),
                       *stats.overruns == 1 ? "" : "s");
  }
  svg.text(width / 2.0, 48.0, subtitle, "middle", 13.0, kMutedColour);

  if (!stats.cycle_histogram || total == stats.cycle_histogram->overflow()) {
    svg.rect(area.left, area.top, area.width, area.height, "none",
             format(" stroke=\"%s\"", kAxisColour));
    svg.text(area.left + area.width / 2.0, area.top + area.height / 2.0,
             "no cycle histogram in the stats", "middle", 14.0, kMutedColour);
    return svg.finish();
  }
  const CycleHistogram& h = *stats.cycle_histogram;
  const std::size_t n = h.upper_us.size();
  const auto lower = [&](std::size_t b) { return b == 0 ? 0.0 : h.upper_us[b - 1]; };
  std::size_t first = n, last = 0;
  for (std::size_t b = 0; b < n; ++b) {
    if (h.counts[b] > 0) {
      first = std::min(first, b);
      last = b;
    }
  }
  // Shown buckets: the occupied range and one empty bucket either side; from 0 when that is close.
  std::size_t b0 = first > 0 ? first - 1 : 0;
  const std::size_t b1 = std::min(last + 1, n - 1);
  if (lower(b0) < 0.35 * h.upper_us[b1]) b0 = 0;
  const double v0 = lower(b0), v1 = h.upper_us[b1];
  bool uniform = true;
  const double w0 = h.upper_us[b1] - lower(b1);
  for (std::size_t b = b0; b <= b1; ++b) {
    uniform = uniform && std::fabs((h.upper_us[b] - lower(b)) - w0) <= 1e-6 * w0;
  }
  const std::size_t shown = b1 - b0 + 1;
  // x: linear when the buckets are even; otherwise each bucket gets the same width.
  const auto x_of = [&](double us) {
    us = std::clamp(us, v0, v1);
    if (uniform) return area.left + (us - v0) / (v1 - v0) * area.width;
    std::size_t b = b0;
    while (b < b1 && us > h.upper_us[b]) ++b;
    const double frac = (us - lower(b)) / (h.upper_us[b] - lower(b));
    return area.left +
           (static_cast<double>(b - b0) + frac) / static_cast<double>(shown) * area.width;
  };
  const bool in_ms = v1 >= 2000.0;
  const double divisor = in_ms ? 1000.0 : 1.0;
  std::vector<Tick> x_ticks;
  if (uniform) {
    const Scale sx{v0, v1, area.left, area.right()};
    x_ticks = make_ticks(sx, nice_step(v1 - v0, 8), divisor);
  } else {
    const std::size_t every = (shown + 9) / 10;
    for (std::size_t b = b0; b <= b1 + 1; b += every) {
      const double v = b == 0 ? 0.0 : h.upper_us[b - 1];
      x_ticks.push_back({x_of(v), format("%g", v / divisor)});
    }
  }
  std::uint64_t peak = 0;
  for (std::size_t b = b0; b <= b1; ++b) peak = std::max(peak, h.counts[b]);
  const double y_step = nice_step(static_cast<double>(peak) * 1.08, 5);
  const double y_top =
      std::max(y_step, std::ceil(static_cast<double>(peak) * 1.08 / y_step - 1e-9) * y_step);
  const Scale sy{0.0, y_top, area.bottom(), area.top};
  std::vector<Tick> y_ticks;
  for (const double v : ticks_in(0.0, y_top, std::max(1.0, y_step))) {
    y_ticks.push_back({sy(v), format("%.0f", v)});
  }
  draw_axes(svg, area, x_ticks, y_ticks, in_ms ? "cycle time (ms)" : "cycle time (µs)", "cycles",
            false);
  svg.raw("<g class=\"bars\">\n");
  for (std::size_t b = b0; b <= b1; ++b) {
    if (h.counts[b] == 0) continue;
    const double xa = x_of(lower(b)), xb = x_of(h.upper_us[b]);
    const double hpx = std::max(1.0, area.bottom() - sy(static_cast<double>(h.counts[b])));
    const double gap = xb - xa > 4.0 ? 0.5 : 0.0;
    svg.rect(xa + gap, area.bottom() - hpx, xb - xa - 2.0 * gap, hpx, "#6b9bd1",
             " stroke=\"#3f6fa8\" stroke-width=\"0.5\"");
  }
  svg.raw("</g>\n");

  // Median and p99 markers, labels on separate rows so that they never collide.
  if (cycle != nullptr) {
    struct Marker {
      double us;
      const char* colour;
      std::string label;
      double row;
    };
    const Marker markers[] = {
        {cycle->median_us, kMedianColour, "median " + duration(cycle->median_us, true), 0.0},
        {cycle->p99_us, kP99Colour, "p99 " + duration(cycle->p99_us, true), 1.0},
    };
    for (const Marker& m : markers) {
      if (!std::isfinite(m.us)) continue;
      const double x = x_of(m.us);
      const double baseline = area.top - 22.0 + 16.0 * m.row;
      svg.line(x, baseline - 10.0, x, area.bottom(), m.colour, 1.8, " stroke-dasharray=\"6,3\"");
      const double w = text_width(m.label, 12.0);
      const bool right_side = x + 6.0 + w < area.right();
      svg.text(right_side ? x + 5.0 : x - 5.0, baseline, m.label, right_side ? "start" : "end",
               12.0, m.colour, " font-weight=\"bold\"");
    }
  }
  std::string caption;
  std::uint64_t hidden_above = h.overflow();
  for (std::size_t b = b1 + 1; b < n; ++b) hidden_above += h.counts[b];
  caption = format("%zu buckets shown, %s to %s", shown,
                   v0 > 0.0 ? duration(v0, true).c_str() : "0", duration(v1, true).c_str());
  if (!uniform) caption += ", uneven buckets drawn at equal width";
  if (hidden_above > 0) {
    caption +=
        format(";  %llu cycle%s above %s not drawn", static_cast<unsigned long long>(hidden_above),
               hidden_above == 1 ? "" : "s", duration(v1, true).c_str());
  }
  if (cycle != nullptr) caption += ";  max " + duration(cycle->max_us, true);
  svg.text(width / 2.0, area.bottom() + 66.0, caption, "middle", 11.5, kMutedColour);
  return svg.finish();
}

std::string stages_svg(const RunStats& stats) {
  const double width = 860.0;
  const double row_h = 34.0;
  double label_w = 0.0;
  for (const StageTiming& s : stats.stages) label_w = std::max(label_w, text_width(s.name, 13.0));
  const double value_w = 230.0;  // room for the value text right of the bars
  const Area area{label_w + 34.0, 84.0, width - label_w - 34.0 - value_w,
                  row_h * static_cast<double>(std::max<std::size_t>(stats.stages.size(), 1))};
  Svg svg(width, area.bottom() + 80.0);
  svg.text(width / 2.0, 26.0, "Per-stage compute time (median and p99)", "middle", 17.0,
           kTextColour, " font-weight=\"bold\"");
  const std::vector<LegendItem> legend = {
      {LegendItem::Kind::kBox, "#9ecae1", "median"},
      {LegendItem::Kind::kBox, "#2171b5", "p99"},
  };
  const double legend_w = draw_legend(svg, 0, 0, legend, false);
  draw_legend(svg, (width - legend_w) / 2.0, 56.0, legend);

  double top_us = 0.0;
  for (const StageTiming& s : stats.stages) {
    if (std::isfinite(s.p99_us)) top_us = std::max(top_us, s.p99_us);
    if (std::isfinite(s.median_us)) top_us = std::max(top_us, s.median_us);
  }
  top_us = std::max(top_us, 1.0);
  const bool in_ms = top_us >= 2000.0;
  const double divisor = in_ms ? 1000.0 : 1.0;
  const double step = nice_step(top_us * 1.02, 6);
  top_us = std::ceil(top_us * 1.02 / step - 1e-9) * step;
  const Scale sx{0.0, top_us, area.left, area.right()};
  draw_axes(svg, area, make_ticks(sx, step, divisor), {},
            in_ms ? "compute time (ms)" : "compute time (µs)", "");

  svg.text(area.right() + 8.0, area.top - 8.0, "median / p99  (max)", "start", 11.5, kMutedColour);
  for (std::size_t i = 0; i < stats.stages.size(); ++i) {
    const StageTiming& s = stats.stages[i];
    const double y = area.top + row_h * static_cast<double>(i);
    if (s.name == "cycle" && i > 0) {
      svg.line(area.left - label_w - 20.0, y, area.right() + value_w - 10.0, y, "#999999", 1.0);
    }
    svg.text(area.left - 10.0, y + row_h / 2.0 + 4.5, s.name, "end", 13.0, kTextColour,
             s.name == "cycle" ? " font-weight=\"bold\"" : "");
    const auto bar = [&](double us, double offset, const char* colour) {
      if (!std::isfinite(us)) return;
      svg.rect(area.left, y + offset, std::max(1.0, sx(std::min(us, top_us)) - area.left), 11.0,
               colour);
    };
    bar(s.median_us, 5.0, "#9ecae1");
    bar(s.p99_us, 17.0, "#2171b5");
    svg.text(area.right() + 8.0, y + row_h / 2.0 + 4.5,
             format("%s / %s  (max %s)", duration(s.median_us, true).c_str(),
                    duration(s.p99_us, true).c_str(), duration(s.max_us, true).c_str()),
             "start", 11.5);
  }
  std::string caption =
      format("cycle budget %s (far right of this scale)", budget(stats.budget_us).c_str());
  if (const StageTiming* cycle = stats.stage("cycle")) {
    if (std::isfinite(cycle->p99_us)) {
      caption = format("cycle budget %s: the cycle's p99 uses %.1f%% of it",
                       budget(stats.budget_us).c_str(), cycle->p99_us / stats.budget_us * 100.0);
    }
  }
  svg.text(width / 2.0, area.bottom() + 62.0, caption, "middle", 11.5, kMutedColour);
  return svg.finish();
}

// ---------------------------------------------------------------------------------------------
// HTML
// ---------------------------------------------------------------------------------------------

namespace {

const char* const kCss = R"(
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; color: #222; margin: 2em auto;
       max-width: 940px; padding: 0 1em; line-height: 1.4; }
h1 { font-size: 1.7em; margin-bottom: 0.1em; }
h2 { font-size: 1.25em; margin-top: 1.8em; border-bottom: 1px solid #ddd; padding-bottom: 0.2em; }
p.subtitle { color: #555; margin-top: 0; font-size: 1.1em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.95em; }
th, td { padding: 0.25em 0.8em; border-bottom: 1px solid #e4e4e4; text-align: right; }
th { background: #f4f4f4; }
td:first-child, th:first-child { text-align: left; }
td.over { color: #c62828; font-weight: bold; }
.files td { text-align: left; font-family: "DejaVu Sans Mono", monospace; font-size: 0.9em; }
figure { margin: 1.2em 0; }
figure img { max-width: 100%; border: 1px solid #e4e4e4; }
figcaption { color: #555; font-size: 0.9em; }
.note { color: #555; font-size: 0.9em; }
.sections { display: flex; flex-wrap: wrap; gap: 0 2em; align-items: flex-start; }
)";

void html_row(std::string& out, const std::string& label, const std::vector<std::string>& cells,
              const std::vector<bool>& over = {}) {
  out += "<tr><td>" + escape(label) + "</td>";
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const bool red = i < over.size() && over[i];
    out += red ? "<td class=\"over\">" : "<td>";
    out += escape(cells[i]) + "</td>";
  }
  out += "</tr>\n";
}

}  // namespace

std::string index_html(const Report& report, const std::vector<std::string>& images) {
  std::string out;
  out +=
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>harmoloc run report</title>\n<style>";
  out += kCss;
  out += "</style>\n</head>\n<body>\n<h1>harmoloc run report</h1>\n";
  if (!report.inputs.title.empty()) {
    out += "<p class=\"subtitle\">" + escape(report.inputs.title) + "</p>\n";
  }

  // Accuracy table: one column per scored set.
  struct Column {
    std::string name;
    const TrajectoryErrors* errors;
    bool heading;
  };
  std::vector<Column> columns = {{"fused estimate", &report.estimate_all, true}};
  const double skip = report.inputs.skip_initial_s;
  if (report.estimate_converged) {
    columns.push_back({"fused, after " + seconds(skip), &*report.estimate_converged, true});
  }
  if (report.fixes_all) columns.push_back({"harmonic fixes", &*report.fixes_all, false});
  if (report.fixes_converged) {
    columns.push_back({"fixes, after " + seconds(skip), &*report.fixes_converged, false});
  }
  out += "<h2>Accuracy against ground truth</h2>\n<table>\n<tr><th></th>";
  for (const Column& c : columns) out += "<th>" + escape(c.name) + "</th>";
  out += "</tr>\n";
  const auto row = [&](const std::string& label, auto value, bool heading_only = false) {
    std::vector<std::string> cells;
    for (const Column& c : columns) {
      cells.push_back(heading_only && !c.heading ? "—" : value(*c.errors));
    }
    html_row(out, label, cells);
  };
  row("poses scored", [](const TrajectoryErrors& e) { return std::to_string(e.count); });
  row("RMSE x (cm)", [](const TrajectoryErrors& e) { return cell(e.rmse_x_m * 100.0, 2); });
  row("RMSE y (cm)", [](const TrajectoryErrors& e) { return cell(e.rmse_y_m * 100.0, 2); });
  row("RMSE position (cm)",
      [](const TrajectoryErrors& e) { return cell(e.rmse_position_m * 100.0, 2); });
  row("MSE x (cm²)", [](const TrajectoryErrors& e) { return cell(e.mse_x_cm2, 2); });
  row("MSE y (cm²)", [](const TrajectoryErrors& e) { return cell(e.mse_y_cm2, 2); });
  row("mean position error (cm)",
      [](const TrajectoryErrors& e) { return cell(e.mean_position_m * 100.0, 2); });
  row("p95 position error (cm)",
      [](const TrajectoryErrors& e) { return cell(e.p95_position_m * 100.0, 2); });
  row("max position error (cm)",
      [](const TrajectoryErrors& e) { return cell(e.max_position_m * 100.0, 2); });
  row(
      "RMSE heading (deg)", [](const TrajectoryErrors& e) { return cell(e.rmse_heading_deg, 2); },
      true);
  row(
      "max heading error (deg)",
      [](const TrajectoryErrors& e) { return cell(e.max_heading_deg, 2); }, true);
  out += "</table>\n";
  std::string note = "Each pose is compared with the ground truth interpolated at its time.";
  if (report.estimate_all.outside_truth > 0) {
    note += format(" %zu estimate poses outside the ground truth's time span were not scored.",
                   report.estimate_all.outside_truth);
  }
  if (skip > 0.0) {
    note += " The “after” columns leave out the first " + seconds(skip) +
            " of the ground truth (convergence).";
  }
  note += " The harmonic localizer gives no heading.";
  out += "<p class=\"note\">" + escape(note) + "</p>\n";

  if (report.stats) {
    const RunStats& s = *report.stats;
    out += "<h2>Run and timing</h2>\n<table>\n";
    const auto opt = [](const std::optional<std::uint64_t>& v) {
      return v ? std::to_string(*v) : std::string("n/a");
    };
    if (!s.harmoloc_version.empty()) html_row(out, "harmoloc version", {s.harmoloc_version});
    if (!s.board.empty()) html_row(out, "board", {s.board});
    html_row(out, "frames", {opt(s.frames)});
    html_row(out, "cycles", {opt(s.cycles)});
    if (s.rate_hz) html_row(out, "rate", {format("%g Hz", *s.rate_hz)});
    html_row(out, "budget per cycle", {budget(s.budget_us)});
    html_row(out, "overruns", {opt(s.overruns)}, {s.overruns && *s.overruns > 0});
    for (const auto& [name, count] : s.degraded) {
      html_row(out, "degraded: " + name + " (cycles)", {std::to_string(count)}, {count > 0});
    }
    if (s.localizer_fixes) html_row(out, "harmonic fixes", {opt(s.localizer_fixes)});
    if (s.localizer_unknown_place) {
      html_row(out, "unknown place (fix refused)", {opt(s.localizer_unknown_place)});
    }
    out += "</table>\n";

    out +=
        "<table>\n<tr><th>stage (µs)</th><th>median</th><th>p99</th><th>p99.9</th>"
        "<th>max</th><th>mean</th><th>p99 / budget</th></tr>\n";
    for (const StageTiming& st : s.stages) {
      const bool over = std::isfinite(st.max_us) && st.max_us > s.budget_us;
      html_row(out, st.name,
               {cell(st.median_us, 1), cell(st.p99_us, 1), cell(st.p999_us, 1), cell(st.max_us, 1),
                cell(st.mean_us, 1), cell(st.p99_us / s.budget_us * 100.0, 2) + " %"},
               {false, false, false, over, false, false});
    }
    out += "</table>\n<p class=\"note\">" +
           escape("Budget " + budget(s.budget_us) +
                  " per cycle; a maximum above it is shown in red.") +
           "</p>\n";
  }

  for (const std::string& image : images) {
    std::string caption;
    if (image == "trajectory.svg") {
      caption = "Ground truth and fused estimate in the map frame (metres, equal aspect).";
    } else if (image == "error.svg") {
      caption = "Position error (cm) and signed heading error (deg) over time.";
    } else if (image == "timing.svg") {
      caption = "Histogram of the whole-cycle compute time with its median and p99.";
    } else if (image == "stages.svg") {
      caption = "Median and p99 compute time of each stage of the cycle.";
    }
    out += "<figure><img src=\"" + escape(image) + "\" alt=\"" + escape(caption) +
           "\"><figcaption>" + escape(caption) + "</figcaption></figure>\n";
  }

  if (report.stats && !report.stats->sections.empty()) {
    out += "<h2>Other statistics</h2>\n<div class=\"sections\">\n";
    for (const StatsSection& section : report.stats->sections) {
      if (section.entries.empty()) continue;
      out += "<table>\n<tr><th>" + escape(section.name) + "</th><th></th></tr>\n";
      for (const auto& [key, value] : section.entries) html_row(out, key, {value});
      out += "</table>\n";
    }
    out += "</div>\n";
  }

  out += "<h2>Inputs</h2>\n<table class=\"files\">\n";
  html_row(out, "ground truth", {report.inputs.truth_path});
  html_row(out, "fused estimate", {report.inputs.estimate_path});
  if (!report.inputs.fixes_path.empty()) {
    html_row(out, "harmonic fixes", {report.inputs.fixes_path});
  }
  if (!report.inputs.stats_path.empty()) html_row(out, "stats", {report.inputs.stats_path});
  out +=
      "</table>\n<p class=\"note\">Written by harmoloc-report. The numbers are also in "
      "<a href=\"summary.json\">summary.json</a> and <a href=\"summary.txt\">summary.txt</a>."
      "</p>\n</body>\n</html>\n";
  return out;
}

std::vector<std::string> write_report(const Report& report, const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw std::runtime_error(dir.string() + ": cannot create the report folder" +
                             (ec ? " (" + ec.message() + ")" : std::string()));
  }
  std::vector<std::string> images;
  std::vector<std::string> written;
  const auto put = [&](const std::string& name, const std::string& content) {
    write_file(dir / name, content);
    written.push_back(name);
  };
  const auto drop = [&](const std::string& name) {
    std::error_code ignored;
    std::filesystem::remove(dir / name, ignored);  // a stale plot of an earlier run
  };
  put("trajectory.svg", trajectory_svg(report));
  images.push_back("trajectory.svg");
  put("error.svg", error_svg(report));
  images.push_back("error.svg");
  if (report.stats && report.stats->cycle_histogram) {
    put("timing.svg", timing_svg(*report.stats));
    images.push_back("timing.svg");
  } else {
    drop("timing.svg");
  }
  if (report.stats && !report.stats->stages.empty()) {
    put("stages.svg", stages_svg(*report.stats));
    images.push_back("stages.svg");
  } else {
    drop("stages.svg");
  }
  put("index.html", index_html(report, images));
  put("summary.json", summary_json(report));
  put("summary.txt", summary_text(report, (dir / "index.html").string()));
  return written;
}

}  // namespace harmoloc::sim_host
