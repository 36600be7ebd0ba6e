#include "harmoloc/dataset/metadata.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <toml++/toml.h>

#include "harmoloc/dataset/toml_writer.hpp"
#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::dataset {

namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error("metadata.toml: " + what);
}

template <typename T>
T number(const toml::table& t, const char* section, const char* key, T lo, T hi, T fallback,
         bool required) {
  const toml::node* node = t.at_path(std::string(section) + "." + key).node();
  if (node == nullptr) {
    if (required) fail(std::string("missing ") + section + "." + key);
    return fallback;
  }
  double v = 0.0;
  if (auto i = node->value_exact<std::int64_t>()) {
    v = static_cast<double>(*i);
  } else if (auto d = node->value_exact<double>()) {
    v = *d;
  } else {
    fail(std::string(section) + "." + key + " must be a number");
  }
  if (!(v >= static_cast<double>(lo) && v <= static_cast<double>(hi))) {
    std::ostringstream s;
    s << section << "." << key << " = " << v << " is outside " << static_cast<double>(lo) << ".."
      << static_cast<double>(hi);
    fail(s.str());
  }
  return static_cast<T>(v);
}

std::string text(const toml::table& t, const char* section, const char* key,
                 const std::string& fallback) {
  const toml::node* node = t.at_path(std::string(section) + "." + key).node();
  if (node == nullptr) return fallback;
  auto s = node->value_exact<std::string>();
  if (!s) fail(std::string(section) + "." + key + " must be a string");
  return *s;
}

}  // namespace

DatasetMetadata read_metadata(const std::string& dataset_dir) {
  const std::string path = (std::filesystem::path(dataset_dir) / "metadata.toml").string();
  if (!std::filesystem::exists(path))
    fail("not found in " + dataset_dir + " (is it a dataset folder?)");
  std::string content;
  if (const std::string e =
          drivers::read_regular_file(path, drivers::input_limits::kTomlBytes, content);
      !e.empty()) {
    fail(e);
  }
  if (const std::string e = drivers::check_toml_nesting(content); !e.empty()) fail(e);
  toml::table t;
  try {
    t = toml::parse(content, path);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << "line " << e.source().begin.line << ": " << e.description();
    fail(s.str());
  }
  DatasetMetadata m;
  // value_exact, not value<>: toml++ 3.3.0's float-to-integer conversion casts before it checks
  // the range (undefined for 2e57; found by the metadata fuzzer), and a version of 1.0 is not 1.
  if (t["format_version"].node() == nullptr) fail("missing format_version");
  const auto version = t["format_version"].value_exact<std::int64_t>();
  if (!version) fail("format_version must be an integer");
  if (*version != 1)
    fail("format_version " + std::to_string(*version) + " is not supported (expected 1)");
  if (t["name"].node() != nullptr) {
    const auto name = t["name"].value_exact<std::string>();
    if (!name) fail("name must be a string");
    m.name = *name;
  }
  std::int64_t seed = 0;
  if (t["seed"].node() != nullptr) {
    const auto s = t["seed"].value_exact<std::int64_t>();
    if (!s) fail("seed must be an integer");
    seed = *s;
  }
  if (seed < 0) fail("seed must not be negative");
  m.seed = static_cast<std::uint64_t>(seed);

  m.image_width_px = number<std::uint32_t>(t, "camera", "width_px", 2, 8192, 0, true);
  m.image_height_px = number<std::uint32_t>(t, "camera", "height_px", 2, 8192, 0, true);
  const std::string format = text(t, "camera", "pixel_format", "rgb24");
  if (format == "rgb24")
    m.pixel_format = hal::PixelFormat::kRgb24;
  else if (format == "yuyv")
    m.pixel_format = hal::PixelFormat::kYuyv;
  else
    fail("camera.pixel_format must be \"rgb24\" or \"yuyv\", not \"" + format + "\"");
  if (m.pixel_format == hal::PixelFormat::kYuyv && m.image_width_px % 2 != 0)
    fail("camera.width_px must be even for yuyv");
  m.frame_rate_hz = number<double>(t, "camera", "rate_hz", 1.0, 1000.0, 30.0, true);
  m.frames_index = text(t, "camera", "frames_index", "frames.csv");
  m.camera_forward_m =
      number<double>(t, "camera", "forward_offset_m", -1.0, 1.0, m.camera_forward_m, false);
  m.camera_height_m = number<double>(t, "camera", "height_m", 0.01, 5.0, m.camera_height_m, false);

  const std::string source = text(t, "encoders", "source", "can");
  if (source == "can")
    m.encoder_source = EncoderSource::kCan;
  else if (source == "gpio")
    m.encoder_source = EncoderSource::kGpio;
  else
    fail("encoders.source must be \"can\" or \"gpio\", not \"" + source + "\"");
  m.encoder_log = text(t, "encoders", "log",
                       m.encoder_source == EncoderSource::kGpio ? "encoders.csv" : "encoders.log");
  m.can_interface = text(t, "encoders", "interface", "can0");
  auto& lay = m.encoder_layout;
  lay.id = number<std::uint32_t>(t, "encoders", "can_id", 0, 0x1FFFFFFF, lay.id, false);
  lay.length = number<std::uint8_t>(t, "encoders", "length", 1, 8, lay.length, false);
  lay.left_offset =
      number<std::uint8_t>(t, "encoders", "left_offset", 0, 7, lay.left_offset, false);
  lay.right_offset =
      number<std::uint8_t>(t, "encoders", "right_offset", 0, 7, lay.right_offset, false);
  lay.counter_bits =
      number<std::uint8_t>(t, "encoders", "counter_bits", 8, 32, lay.counter_bits, false);
  const std::string order = text(t, "encoders", "byte_order", "little");
  if (order == "little")
    lay.byte_order = algorithms::ByteOrder::kLittleEndian;
  else if (order == "big")
    lay.byte_order = algorithms::ByteOrder::kBigEndian;
  else
    fail("encoders.byte_order must be \"little\" or \"big\"");
  if (!algorithms::layout_valid(lay))
    fail("encoders: counters do not fit in the frame (offsets, counter_bits, length)");

  auto& g = m.geometry;
  g.wheel_radius_m =
      number<double>(t, "robot", "wheel_radius_m", 0.001, 10.0, g.wheel_radius_m, true);
  g.track_m = number<double>(t, "robot", "track_m", 0.001, 100.0, g.track_m, true);
  g.ticks_per_rev = number<double>(t, "robot", "ticks_per_rev", 1.0, 1e9, g.ticks_per_rev, true);
  g.left_direction = number<int>(t, "robot", "left_direction", -1, 1, 1, false);
  g.right_direction = number<int>(t, "robot", "right_direction", -1, 1, 1, false);
  if (g.left_direction == 0 || g.right_direction == 0) fail("robot.*_direction must be 1 or -1");

  m.ground_truth = text(t, "ground_truth", "file", "");
  // The files the metadata names are the dataset's own: inside its folder (a path out of it
  // could name /dev/zero, a FIFO or another user's file).
  const auto inside = [&dataset_dir](const std::string& key, const std::string& value) {
    if (const std::string e = drivers::check_inside(dataset_dir, value); !e.empty())
      fail(key + " '" + value + "' " + e);
  };
  inside("camera.frames_index", m.frames_index);
  inside("encoders.log", m.encoder_log);
  if (!m.ground_truth.empty()) inside("ground_truth.file", m.ground_truth);
  return m;
}

std::string metadata_toml(const DatasetMetadata& m) {
  TomlWriter w("harmoloc dataset metadata (schema: docs/dataset-format.md)");
  w.set("format_version", 1).set("name", m.name).set("seed", m.seed);
  w.table("camera")
      .set("width_px", m.image_width_px)
      .set("height_px", m.image_height_px)
      .set("pixel_format", m.pixel_format == hal::PixelFormat::kRgb24 ? "rgb24" : "yuyv")
      .set("rate_hz", m.frame_rate_hz)
      .set("frames_index", m.frames_index);
  if (std::isfinite(m.camera_forward_m)) w.set("forward_offset_m", m.camera_forward_m);
  if (std::isfinite(m.camera_height_m)) w.set("height_m", m.camera_height_m);
  // A CAN dataset's metadata does not name the source (the files written before it existed).
  w.table("encoders");
  if (m.encoder_source == EncoderSource::kGpio) w.set("source", "gpio");
  const auto& lay = m.encoder_layout;
  w.set("log", m.encoder_log)
      .set("interface", m.can_interface)
      .set_hex("can_id", lay.id)
      .set("length", int{lay.length})
      .set("left_offset", int{lay.left_offset})
      .set("right_offset", int{lay.right_offset})
      .set("counter_bits", int{lay.counter_bits})
      .set("byte_order", lay.byte_order == algorithms::ByteOrder::kLittleEndian ? "little" : "big");
  w.table("robot")
      .set("wheel_radius_m", m.geometry.wheel_radius_m)
      .set("track_m", m.geometry.track_m)
      .set("ticks_per_rev", m.geometry.ticks_per_rev)
      .set("left_direction", m.geometry.left_direction)
      .set("right_direction", m.geometry.right_direction);
  if (!m.ground_truth.empty()) w.table("ground_truth").set("file", m.ground_truth);
  return w.text();
}

void write_metadata(const std::string& dataset_dir, const DatasetMetadata& m) {
  const std::string path = (std::filesystem::path(dataset_dir) / "metadata.toml").string();
  std::string text;
  try {
    text = metadata_toml(m);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  out << text;
  if (!out) throw std::runtime_error(path + ": write failed");
}

}  // namespace harmoloc::dataset
