#pragma once
/// @file The SVG toolkit of the host tools' plots: XML escaping, the number format of
/// coordinates, and a canvas that writes the elements. Axes and legends are in svg_plot.hpp,
/// tick steps in svg_ticks.hpp. Host only; allocates freely.

#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace harmoloc::sim_host::svg {

inline constexpr const char* kFont = "DejaVu Sans, Helvetica, Arial, sans-serif";
inline constexpr const char* kGridColour = "#e6e6e6";
inline constexpr const char* kAxisColour = "#555555";
inline constexpr const char* kTextColour = "#222222";
inline constexpr const char* kMutedColour = "#666666";

/// Escapes text for XML/HTML content and attribute values (quotes included, so that either
/// quoting style is safe).
std::string escape(const std::string& text);

/// A coordinate with one decimal; values within 0.05 of zero print as "0.0", not "-0.0".
std::string number(double v);

/// Approximate rendered width of @p text at @p size px (DejaVu Sans averages ~0.6 em); there is
/// no font metrics on a headless host, and the layouts only need to avoid overlaps.
double text_width(const std::string& text, double size);

/// @p document without its XML declaration, for an <svg> element inside an HTML page.
std::string inline_svg(const std::string& document);

/// A standalone SVG document being written, white background first. Colours are code
/// constants and pass through; text content is escaped. @p extra is appended raw inside the
/// element (further attributes, each with a leading space).
class Canvas {
 public:
  Canvas(double width, double height);

  double width() const { return width_; }
  double height() const { return height_; }

  void raw(const std::string& text) { out_ << text; }
  void line(double x1, double y1, double x2, double y2, const char* stroke, double stroke_width,
            const std::string& extra = "");
  void rect(double x, double y, double w, double h, const char* fill,
            const std::string& extra = "");
  void circle(double x, double y, double r, const char* fill, const std::string& extra = "");
  void text(double x, double y, const std::string& content, const char* anchor = "start",
            double size = 12.0, const char* fill = kTextColour, const std::string& extra = "");
  void polyline(const std::vector<std::pair<double, double>>& points, const char* stroke,
                double stroke_width, const std::string& css_class, const std::string& extra = "");

  /// Closes the document and returns it.
  std::string finish();

 private:
  double width_;
  double height_;
  std::ostringstream out_;
};

}  // namespace harmoloc::sim_host::svg
