#pragma once
/// @file The Linux board's pieces for its main: its command line, the devices the config names
/// (docs/drivers.md) and its part of the shared run loop (the cycle pacer, the service's
/// watchdog and status, health changes for the journal, --cycles and --duration).

#include <cstdint>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "application.hpp"
#include "health_log.hpp"

#include "harmoloc/drivers/service_notifier.hpp"
#include "harmoloc/drivers/socketcan_encoders.hpp"
#include "harmoloc/drivers/v4l2_camera.hpp"
#ifdef HARMOLOC_WITH_GPIOD
#include "harmoloc/drivers/gpio_quadrature_encoders.hpp"
#endif
#ifdef HARMOLOC_WITH_LIBCAMERA
#include "harmoloc/drivers/libcamera_camera.hpp"
#endif

namespace harmoloc::boards {

struct LinuxOptions {
  AppOptions app;
  double duration_s = 0.0;
  std::uint64_t max_cycles = 0;
};

void add_linux_options(CLI::App& app, LinuxOptions& o);

/// The camera (V4L2 or libcamera) and the wheel encoders (SocketCAN or GPIO quadrature) that
/// the config names, opened and checked.
class LinuxDevices {
 public:
  /// Each returns "" or one line saying why not.
  std::string open_camera(const firmware::FirmwareConfig& config, hal::Clock& clock);
  std::string open_encoders(const firmware::FirmwareConfig& config);
  hal::Camera& camera() { return *camera_; }
  hal::PixelFormat pixel_format() const { return pixel_format_; }
  hal::WheelEncoders& encoders() { return *encoders_; }
  /// What a --record folder of this run says about the camera and the robot.
  dataset::DatasetMetadata recorded(const firmware::FirmwareConfig& config) const;
  const std::string& camera_text() const { return camera_text_; }
  const std::string& encoders_text() const { return encoders_text_; }

 private:
  std::unique_ptr<drivers::V4l2Camera> v4l2_;
#ifdef HARMOLOC_WITH_LIBCAMERA
  std::unique_ptr<drivers::LibcameraCamera> libcam_;
#endif
  std::unique_ptr<drivers::SocketCanEncoders> can_;
#ifdef HARMOLOC_WITH_GPIOD
  std::unique_ptr<drivers::GpioQuadratureEncoders> gpio_;
#endif
  hal::Camera* camera_ = nullptr;
  hal::PixelFormat pixel_format_ = hal::PixelFormat::kYuyv;
  hal::WheelEncoders* encoders_ = nullptr;
  std::string camera_text_, encoders_text_;
};

/// Paced by the cycle pacer (camera or timer); feeds the service's watchdog, says health
/// changes, and stops at --cycles or --duration.
class LinuxLoop final : public BoardLoop {
 public:
  LinuxLoop(const LinuxOptions& options, const firmware::FirmwareConfig& config,
            firmware::CyclePacer& pacer, hal::Clock& clock, drivers::ServiceNotifier& notifier,
            HealthLog& health_log)
      : options_(options),
        config_(config),
        pacer_(pacer),
        clock_(clock),
        notifier_(notifier),
        health_log_(health_log) {}
  firmware::CycleResult run_cycle(firmware::LocalizationCycle& cycle) override {
    return cycle.run_once(pacer_.wait_for_cycle());
  }
  void started(std::uint64_t start_ns) override;
  const char* after_cycle(const firmware::LocalizationCycle& cycle, std::uint64_t cycles) override;
  void stopping(const char* ended, std::uint64_t cycles) override;

 private:
  const LinuxOptions& options_;
  const firmware::FirmwareConfig& config_;
  firmware::CyclePacer& pacer_;
  hal::Clock& clock_;
  drivers::ServiceNotifier& notifier_;
  HealthLog& health_log_;
  std::uint64_t end_ns_ = 0;
};

}  // namespace harmoloc::boards
