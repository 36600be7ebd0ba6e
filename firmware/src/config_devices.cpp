// The Linux board's devices in the config: [camera], [encoders], link.device (docs/drivers.md).
#include "config_checker.hpp"

namespace harmoloc::firmware::config_detail {

namespace {

std::string one_of(const Checker& check, const toml::table& t, const char* key,
                   const std::string& where, const std::string& fallback,
                   std::initializer_list<const char*> allowed) {
  const std::string v = check.text(t, key, where, fallback);
  std::string list;
  for (const char* a : allowed) {
    if (v == a) return v;
    list += std::string(list.empty() ? "" : ", ") + "\"" + a + "\"";
  }
  check.fail(t.get(key), where + key + " must be one of " + list);
}

std::array<unsigned, 2> line_pair(const Checker& check, const toml::table& t, const char* key,
                                  const std::array<unsigned, 2>& fallback) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return fallback;
  const toml::array* a = n->as_array();
  const std::string what = std::string("encoders.") + key + " must be [A, B] line offsets 0..1023";
  if (a == nullptr || a->size() != 2) check.fail(n, what);
  std::array<unsigned, 2> out{};
  for (std::size_t k = 0; k < 2; ++k) {
    const auto v = a->get(k)->value_exact<std::int64_t>();
    if (!v || *v < 0 || *v > 1023) check.fail(a->get(k), what);
    out[k] = static_cast<unsigned>(*v);
  }
  return out;
}

}  // namespace

void read_device_sections(const Checker& check, const toml::table& root, FirmwareConfig& c) {
  if (const toml::table* t = check.section(root, "camera")) {
    check.only(*t, "camera.",
               {"driver", "device", "width", "height", "format", "buffers", "reopen_interval_ms",
                "height_m", "forward_offset_m"});
    auto& k = c.camera;
    k.driver = one_of(check, *t, "driver", "camera.", k.driver, {"v4l2", "libcamera"});
    // libcamera names cameras by id; "" picks the first. A v4l2 device needs a path.
    k.device = check.text(*t, "device", "camera.", k.driver == "libcamera" ? "" : k.device);
    if (k.driver == "v4l2" && k.device.empty())
      check.fail(t->get("device"), "camera.device must name a V4L2 device node");
    k.width_px =
        static_cast<std::uint32_t>(check.integer(*t, "width", "camera.", k.width_px, 16, 8192));
    k.height_px =
        static_cast<std::uint32_t>(check.integer(*t, "height", "camera.", k.height_px, 16, 8192));
    k.format = one_of(check, *t, "format", "camera.", k.format, {"auto", "yuyv", "rgb24"});
    if (k.format != "rgb24" && k.width_px % 2 != 0)
      check.fail(t->get("width"), "camera.width must be even for YUYV");
    k.buffers =
        static_cast<std::uint32_t>(check.integer(*t, "buffers", "camera.", k.buffers, 2, 8));
    k.reopen_interval_ms = static_cast<std::uint32_t>(
        check.integer(*t, "reopen_interval_ms", "camera.", k.reopen_interval_ms, 10, 600000));
    k.mount_height_m = check.number(*t, "height_m", "camera.", k.mount_height_m, 0.01, 5.0);
    k.mount_forward_m =
        check.number(*t, "forward_offset_m", "camera.", k.mount_forward_m, -1.0, 1.0);
  }
  if (const toml::table* t = check.section(root, "encoders")) {
    check.only(*t, "encoders.",
               {"driver", "can_kernel_filter", "gpio_chip", "left_lines", "right_lines",
                "debounce_us", "gpio_reader"});
    auto& e = c.encoders;
    e.driver = one_of(check, *t, "driver", "encoders.", e.driver, {"can", "gpio"});
    if (const toml::node* n = t->get("can_kernel_filter")) {
      const auto b = n->value_exact<bool>();
      if (!b) check.fail(n, "encoders.can_kernel_filter must be true or false");
      e.can_kernel_filter = *b;
    }
    e.gpio_chip = check.text(*t, "gpio_chip", "encoders.", e.gpio_chip);
    if (e.gpio_chip.empty()) check.fail(t->get("gpio_chip"), "encoders.gpio_chip is empty");
    e.left_lines = line_pair(check, *t, "left_lines", e.left_lines);
    e.right_lines = line_pair(check, *t, "right_lines", e.right_lines);
    const unsigned all[4] = {e.left_lines[0], e.left_lines[1], e.right_lines[0], e.right_lines[1]};
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < i; ++j)
        if (all[i] == all[j])
          check.fail(t, "encoders: line " + std::to_string(all[i]) + " is used twice");
    e.debounce_us = static_cast<std::uint32_t>(
        check.integer(*t, "debounce_us", "encoders.", e.debounce_us, 0, 1000000));
    e.gpio_reader =
        one_of(check, *t, "gpio_reader", "encoders.", e.gpio_reader, {"thread", "cycle"});
  }
  if (const toml::table* t = check.section(root, "link")) {
    c.link.device = check.text(*t, "device", "link.", c.link.device);
    if (c.link.device.empty()) check.fail(t->get("device"), "link.device is empty");
  }
}

}  // namespace harmoloc::firmware::config_detail
