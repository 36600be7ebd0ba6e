// The Linux board's device sections of the config: [camera], [encoders], link.device.
#include <gtest/gtest.h>

#include <string>

#include "harmoloc/firmware/config.hpp"
#include "test_support.hpp"

namespace hf = harmoloc::firmware;
namespace ht = harmoloc::test;

namespace {

std::string error_for(const ht::TempDir& dir, const std::string& text) {
  const std::string file = dir.write("devices.toml", text);
  const std::string msg = ht::error_of([&] { hf::load_config(file); });
  if (msg != ht::kNoException) ht::expect_one_line(msg, file + ": ", "");
  return msg;
}

}  // namespace

TEST(DeviceConfig, Defaults) {
  const hf::FirmwareConfig c = hf::default_config();
  EXPECT_EQ(c.camera.driver, "v4l2");
  EXPECT_EQ(c.camera.device, "/dev/video0");
  EXPECT_EQ(c.camera.width_px, 320U);
  EXPECT_EQ(c.camera.height_px, 240U);
  EXPECT_EQ(c.camera.format, "auto");
  EXPECT_EQ(c.camera.buffers, 4U);
  EXPECT_EQ(c.encoders.driver, "can");
  EXPECT_TRUE(c.encoders.can_kernel_filter);
  EXPECT_EQ(c.encoders.gpio_reader, "thread");
  EXPECT_EQ(c.link.device, "/dev/serial0");
}

TEST(DeviceConfig, EveryKeyIsRead) {
  ht::TempDir dir;
  const std::string file = dir.write("devices.toml", R"(
[camera]
driver = "libcamera"
device = "/base/soc/i2c0mux/i2c@1/imx219@10"
width = 640
height = 360
format = "rgb24"
buffers = 6
reopen_interval_ms = 250
height_m = 0.42
forward_offset_m = -0.05

[encoders]
driver = "gpio"
can_kernel_filter = false
gpio_chip = "gpio-sim.0-node0"
left_lines = [4, 5]
right_lines = [7, 6]
debounce_us = 200
gpio_reader = "cycle"

[link]
device = "/dev/ttyS1"
baud = 921600
)");
  const hf::FirmwareConfig c = hf::load_config(file);
  EXPECT_EQ(c.camera.driver, "libcamera");
  EXPECT_EQ(c.camera.device, "/base/soc/i2c0mux/i2c@1/imx219@10");
  EXPECT_EQ(c.camera.width_px, 640U);
  EXPECT_EQ(c.camera.height_px, 360U);
  EXPECT_EQ(c.camera.format, "rgb24");
  EXPECT_EQ(c.camera.buffers, 6U);
  EXPECT_EQ(c.camera.reopen_interval_ms, 250U);
  EXPECT_DOUBLE_EQ(c.camera.mount_height_m, 0.42);
  EXPECT_DOUBLE_EQ(c.camera.mount_forward_m, -0.05);
  EXPECT_EQ(c.encoders.driver, "gpio");
  EXPECT_FALSE(c.encoders.can_kernel_filter);
  EXPECT_EQ(c.encoders.gpio_chip, "gpio-sim.0-node0");
  EXPECT_EQ(c.encoders.left_lines[0], 4U);
  EXPECT_EQ(c.encoders.left_lines[1], 5U);
  EXPECT_EQ(c.encoders.right_lines[0], 7U);
  EXPECT_EQ(c.encoders.right_lines[1], 6U);
  EXPECT_EQ(c.encoders.debounce_us, 200U);
  EXPECT_EQ(c.encoders.gpio_reader, "cycle");
  EXPECT_EQ(c.link.device, "/dev/ttyS1");
  EXPECT_EQ(c.link.baud, 921600U);
}

TEST(DeviceConfig, LibcameraWithoutDevicePicksTheFirstCamera) {
  ht::TempDir dir;
  const hf::FirmwareConfig c =
      hf::load_config(dir.write("c.toml", "[camera]\ndriver = \"libcamera\"\n"));
  EXPECT_EQ(c.camera.device, "");
}

TEST(DeviceConfig, BadValuesGiveOneLine) {
  ht::TempDir dir;
  EXPECT_NE(error_for(dir, "[camera]\ndriver = \"usb\"\n").find("camera.driver must be one of"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[camera]\nformat = \"mjpeg\"\n").find("camera.format must be one of"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[camera]\nwidth = 8\n").find("camera.width = 8 is outside"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[camera]\nwidth = 321\n").find("must be even for YUYV"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[camera]\nbuffers = 1\n").find("camera.buffers"), std::string::npos);
  EXPECT_NE(error_for(dir, "[camera]\ndevice = \"\"\n").find("camera.device must name"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[camera]\nfps = 30\n").find("unknown key 'camera.fps'"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[camera]\nheight_m = 0\n").find("camera.height_m = 0 is outside"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[camera]\nforward_offset_m = \"ahead\"\n")
                .find("camera.forward_offset_m must be a number"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[encoders]\ndriver = \"spi\"\n").find("encoders.driver must be one of"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[encoders]\nleft_lines = [1]\n").find("encoders.left_lines must be"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[encoders]\nleft_lines = [1, 2]\nright_lines = [2, 3]\n")
                .find("line 2 is used twice"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[encoders]\ncan_kernel_filter = 1\n").find("true or false"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[encoders]\ngpio_reader = \"irq\"\n").find("encoders.gpio_reader"),
            std::string::npos);
  EXPECT_NE(error_for(dir, "[link]\ndevice = \"\"\n").find("link.device is empty"),
            std::string::npos);
  EXPECT_EQ(error_for(dir, "[camera]\ndriver = \"v4l2\"\n"), ht::kNoException)
      << "a valid section must pass (negative control)";
}
