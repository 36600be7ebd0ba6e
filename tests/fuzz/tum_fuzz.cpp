// Fuzz target: TUM trajectory files (dataset::read_tum: ground truth, labels, estimates). Each
// input is written to a file in this process's scratch directory. std::runtime_error is the
// documented answer to a bad file; anything else is a finding. Accepted poses must be finite
// with increasing timestamps.

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "harmoloc/dataset/tum.hpp"

using namespace harmoloc;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = fuzz::scratch_dir() + "/trajectory.tum";
  fuzz::write_file(path, data, size);
  std::vector<dataset::StampedPose> poses;
  try {
    poses = dataset::read_tum(path);
  } catch (const std::runtime_error& e) {
    HARMOLOC_FUZZ_CHECK(e.what() != nullptr && e.what()[0] != '\0', "empty error message");
    return 0;
  }
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const dataset::StampedPose& p = poses[i];
    HARMOLOC_FUZZ_CHECK(
        std::isfinite(p.t_s) && std::isfinite(p.pose.x_m) && std::isfinite(p.pose.y_m),
        "non-finite pose accepted");
    if (i > 0) HARMOLOC_FUZZ_CHECK(p.t_s > poses[i - 1].t_s, "timestamps not increasing");
  }
  if (poses.size() >= 2) {
    // The report tool interpolates the truth at each estimate's time (exercised for memory
    // safety only: finite but extreme inputs may legitimately overflow to inf there).
    const double t = 0.5 * poses.front().t_s + 0.5 * poses.back().t_s;
    algorithms::Pose2 pose;
    (void)dataset::interpolate(poses, t, pose);
  }
  return 0;
}
