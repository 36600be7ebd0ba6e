#include "harmoloc/sim_host/svg.hpp"

#include <algorithm>
#include <cmath>

#include "format.hpp"

namespace harmoloc::sim_host::svg {

using report_text::format;

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

std::string number(double v) {
  if (std::fabs(v) < 0.05) v = 0.0;
  return format("%.1f", v);
}

double text_width(const std::string& text, double size) {
  return 0.6 * size * static_cast<double>(text.size());
}

std::string inline_svg(const std::string& document) {
  if (document.rfind("<?xml", 0) != 0) return document;
  const std::size_t end = document.find("?>");
  if (end == std::string::npos) return document;
  std::size_t start = end + 2;
  while (start < document.size() && document[start] == '\n') ++start;
  return document.substr(start);
}

Canvas::Canvas(double width, double height) : width_(width), height_(height) {
  out_ << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
       << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << number(width) << "\" height=\""
       << number(height) << "\" viewBox=\"0 0 " << number(width) << ' ' << number(height)
       << "\" font-family=\"" << kFont << "\" font-size=\"12\">\n"
       << "<rect x=\"0\" y=\"0\" width=\"" << number(width) << "\" height=\"" << number(height)
       << "\" fill=\"#ffffff\"/>\n";
}

void Canvas::line(double x1, double y1, double x2, double y2, const char* stroke,
                  double stroke_width, const std::string& extra) {
  out_ << "<line x1=\"" << number(x1) << "\" y1=\"" << number(y1) << "\" x2=\"" << number(x2)
       << "\" y2=\"" << number(y2) << "\" stroke=\"" << stroke << "\" stroke-width=\""
       << format("%.2g", stroke_width) << '"' << extra << "/>\n";
}

void Canvas::rect(double x, double y, double w, double h, const char* fill,
                  const std::string& extra) {
  out_ << "<rect x=\"" << number(x) << "\" y=\"" << number(y) << "\" width=\""
       << number(std::max(0.0, w)) << "\" height=\"" << number(std::max(0.0, h)) << "\" fill=\""
       << fill << '"' << extra << "/>\n";
}

void Canvas::circle(double x, double y, double r, const char* fill, const std::string& extra) {
  out_ << "<circle cx=\"" << number(x) << "\" cy=\"" << number(y) << "\" r=\"" << format("%.2g", r)
       << "\" fill=\"" << fill << '"' << extra << "/>\n";
}

void Canvas::text(double x, double y, const std::string& content, const char* anchor, double size,
                  const char* fill, const std::string& extra) {
  out_ << "<text x=\"" << number(x) << "\" y=\"" << number(y) << "\" text-anchor=\"" << anchor
       << "\" font-size=\"" << format("%g", size) << "\" fill=\"" << fill << '"' << extra << '>'
       << escape(content) << "</text>\n";
}

void Canvas::polyline(const std::vector<std::pair<double, double>>& points, const char* stroke,
                      double stroke_width, const std::string& css_class, const std::string& extra) {
  out_ << "<polyline class=\"" << css_class << "\" fill=\"none\" stroke=\"" << stroke
       << "\" stroke-width=\"" << format("%.2g", stroke_width)
       << "\" stroke-linejoin=\"round\" stroke-linecap=\"round\"" << extra << " points=\"";
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (i > 0) out_ << ' ';
    out_ << number(points[i].first) << ',' << number(points[i].second);
  }
  out_ << "\"/>\n";
}

std::string Canvas::finish() {
  out_ << "</svg>\n";
  return out_.str();
}

}  // namespace harmoloc::sim_host::svg
