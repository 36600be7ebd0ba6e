#include "harmoloc/dataset/tum_writer.hpp"

#include "harmoloc/dataset/tum.hpp"

namespace harmoloc::dataset {

void TumWriter::write(std::uint64_t t_ns, const algorithms::Pose2& pose) {
  if (!out_.is_open()) return;
  char line[160];
  const double t_s = static_cast<double>(t_ns / 1000U) * 1e-6;
  const int n = format_tum_line(line, sizeof line, t_s, pose);
  if (n > 0) out_.append(line, static_cast<std::size_t>(n));
}

}  // namespace harmoloc::dataset
