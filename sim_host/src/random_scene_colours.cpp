// The colours of a random scene: the room's greys, the boards' hues and names, and the colour
// windows (and the firmware configuration) a careful user would set for them.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "harmoloc/dataset/toml_writer.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "random_scene_parts.hpp"

namespace harmoloc::sim_host::random_scene_detail {

namespace {

Rgb hsv_to_rgb(double hue_deg, double s, double v) {
  hue_deg = std::fmod(std::fmod(hue_deg, 360.0) + 360.0, 360.0);
  const double c = v * s;
  const double x = c * (1.0 - std::fabs(std::fmod(hue_deg / 60.0, 2.0) - 1.0));
  const double m = v - c;
  double r = 0, g = 0, b = 0;
  switch (static_cast<int>(hue_deg / 60.0)) {
    case 0:
      r = c, g = x;
      break;
    case 1:
      r = x, g = c;
      break;
    case 2:
      g = c, b = x;
      break;
    case 3:
      g = x, b = c;
      break;
    case 4:
      r = x, b = c;
      break;
    default:
      r = c, b = x;
      break;
  }
  const auto byte = [m](double t) {
    return static_cast<std::uint8_t>(std::clamp(std::lround(t + m), 0L, 255L));
  };
  return Rgb{byte(r), byte(g), byte(b)};
}

double saturation_of(const Rgb& c) {
  double h = 0, s = 0, v = 0;
  hsv_of(c, h, s, v);
  return s;
}

std::string hue_name(double h) {
  struct Band {
    double upto;
    const char* name;
  };
  static const Band bands[] = {{12, "red"},     {40, "orange"},   {68, "yellow"}, {100, "lime"},
                               {150, "green"},  {190, "cyan"},    {225, "azure"}, {255, "blue"},
                               {285, "violet"}, {320, "magenta"}, {345, "pink"},  {361, "crimson"}};
  for (const Band& b : bands) {
    if (h < b.upto) return b.name;
  }
  return "red";
}

}  // namespace

// A desaturated colour: 8-bit HSV saturation s8, value v8.
Rgb grey(double hue_deg, double s8, double v8) {
  return hsv_to_rgb(hue_deg, s8 / 255.0, v8);
}

// Hues spread evenly round the circle from a random start (jittered by up to 10% of the
// spacing), assigned in random order; saturated colours.
void colour_boards(Draw& d, std::vector<BoardSpec>& boards) {
  const std::size_t n = boards.size();
  const double spacing = 360.0 / static_cast<double>(n);
  const double start = d.u(0.0, 360.0);
  std::vector<double> hues;
  for (std::size_t k = 0; k < n; ++k)
    hues.push_back(std::fmod(
        start + static_cast<double>(k) * spacing + d.u(-0.1, 0.1) * spacing + 360.0, 360.0));
  for (std::size_t k = n; k > 1; --k)
    std::swap(hues[k - 1], hues[static_cast<std::size_t>(d.i(0, static_cast<int>(k) - 1))]);
  std::vector<std::string> names;
  for (std::size_t k = 0; k < n; ++k) {
    boards[k].colour = hsv_to_rgb(hues[k], d.u(0.75, 1.0), d.u(165.0, 200.0));
    double h = 0, sat = 0, val = 0;
    hsv_of(boards[k].colour, h, sat, val);
    std::string name = hue_name(h);
    const auto same = std::count(names.begin(), names.end(), name);
    names.push_back(name);
    boards[k].name = same == 0 ? name : name + std::to_string(same + 1);
  }
}

}  // namespace harmoloc::sim_host::random_scene_detail

namespace harmoloc::sim_host {

using namespace random_scene_detail;

std::vector<std::pair<std::string, algorithms::ColourThreshold>> thresholds_for(const Scenario& s) {
  std::vector<std::pair<std::string, algorithms::ColourThreshold>> out;
  // Saturation: between the most saturated thing in the room that is not a board and the least
  // saturated board. People walking through are not counted (they come and go; the variants'
  // people are dressed at most as saturated as the walls), so that a scene and its derived runs
  // share one set of windows, and a map trained on the one serves the others.
  double room_s = 0.0;
  for (const Rgb& c : {s.room.floor_colour, s.room.floor_tile_colour, s.room.wall_colour,
                       s.room.side_wall_colour, s.room.ceiling_colour, Rgb{80, 80, 80}})
    room_s = std::max(room_s, saturation_of(c));
  if (s.desk.present)
    room_s = std::max({room_s, saturation_of(s.desk.colour), saturation_of(s.desk.top_colour)});
  double board_s = 255.0, board_v = 255.0;
  std::vector<double> hues;
  for (const BoardSpec& b : s.boards) {
    double h = 0, sat = 0, val = 0;
    hsv_of(b.colour, h, sat, val);
    hues.push_back(h);
    board_s = std::min(board_s, sat);
    board_v = std::min(board_v, val);
  }
  double sat_min = room_s + 0.45 * (board_s - room_s);
  sat_min = std::clamp(sat_min, std::min(room_s + 30.0, board_s - 30.0), board_s - 30.0);
  // Value: the darkest a board can look (its face turned away: 0.8; the vignetting's darkest
  // corner; the lighting at -30%), with room to spare for the noise.
  const double widest = widest_ray_rad(s.camera);
  const double vignette = 1.0 - s.camera.vignetting * (1.0 - std::pow(std::cos(widest), 4.0));
  const double darkest = board_v * 0.8 * vignette * kMinGain;
  const double value_min = std::max(15.0, std::floor(0.55 * darkest));
  for (std::size_t k = 0; k < s.boards.size(); ++k) {
    double gap = 180.0;
    for (std::size_t j = 0; j < hues.size(); ++j) {
      if (j != k) gap = std::min(gap, std::fabs(std::remainder(hues[k] - hues[j], 360.0)));
    }
    const double half = std::clamp(0.5 * gap - 4.0, 5.0, 20.0);
    double lo = hues[k] - half, hi = hues[k] + half;
    if (lo < 0.0) lo += 360.0;
    if (hi >= 360.0) hi -= 360.0;
    algorithms::ColourThreshold t;
    t.hue_min_deg = static_cast<float>(q(lo, 10.0));
    t.hue_max_deg = static_cast<float>(q(hi, 10.0));
    t.saturation_min = static_cast<std::uint8_t>(std::lround(sat_min));
    t.value_min = static_cast<std::uint8_t>(value_min);
    t.value_max = 255;
    out.emplace_back(s.boards[k].name, t);
  }
  return out;
}

algorithms::ThresholdSet threshold_set(
    const std::vector<std::pair<std::string, algorithms::ColourThreshold>>& windows) {
  algorithms::ThresholdSet set;
  set.count = std::min(windows.size(), algorithms::kMaxBoards);
  for (std::size_t k = 0; k < set.count; ++k) set.boards[k] = windows[k].second;
  return set;
}

std::string firmware_config_toml(const Scenario& s) {
  dataset::TomlWriter w("harmoloc firmware configuration for the simulated scene '" + s.name +
                        "' (docs/config-format.md):\nthe robot's nominal geometry, its encoder "
                        "frames and a colour window per board.");
  w.table("odometry")
      .set("wheel_radius_m", s.robot.wheel_radius_m)
      .set("track_m", s.robot.track_m)
      .set("ticks_per_rev", s.robot.ticks_per_rev);
  w.table("can")
      .set("encoder_id", s.can_layout.id)
      .set("length", int{s.can_layout.length})
      .set("left_offset", int{s.can_layout.left_offset})
      .set("right_offset", int{s.can_layout.right_offset})
      .set("counter_bits", int{s.can_layout.counter_bits});
  for (const auto& [name, t] : thresholds_for(s)) {
    toml::array hue;
    dataset::push_number(hue, dataset::decimal_of(t.hue_min_deg));
    dataset::push_number(hue, dataset::decimal_of(t.hue_max_deg));
    w.array_table("board")
        .set("name", name)
        .set("hue_deg", hue)
        .set("saturation_min", int{t.saturation_min})
        .set("value_min", int{t.value_min})
        .set("value_max", int{t.value_max});
  }
  return w.text();
}

}  // namespace harmoloc::sim_host
