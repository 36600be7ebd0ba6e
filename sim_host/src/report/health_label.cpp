// The health's name as the report's plots and tables print it. Apart from link_log.cpp so that
// the report's pages do not need the firmware's MAVLink code.
#include "harmoloc/sim_host/link_log.hpp"

namespace harmoloc::sim_host {

const char* health_label(firmware::Health health) {
  switch (health) {
    case firmware::Health::kNotInitialized:
      return "not initialised";
    case firmware::Health::kNominal:
      return "nominal";
    case firmware::Health::kOdometryOnly:
      return "odometry only";
    case firmware::Health::kVisionOnly:
      return "vision only";
    case firmware::Health::kInvalid:
      return "invalid";
  }
  return "unknown";
}

}  // namespace harmoloc::sim_host
