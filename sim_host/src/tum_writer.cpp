#include "harmoloc/sim_host/tum_writer.hpp"

#include "harmoloc/sim_host/tum.hpp"

namespace harmoloc::sim_host {

bool TumWriter::open(const std::string& path) {
  close();
  file_ = std::fopen(path.c_str(), "w");
  if (file_ == nullptr) return false;
  buffer_ = new char[kBufferBytes];  // start-up: stdio would otherwise allocate on the first write
  std::setvbuf(file_, buffer_, _IOFBF, kBufferBytes);
  return true;
}

void TumWriter::write(std::uint64_t t_ns, const algorithms::Pose2& pose) {
  if (file_ == nullptr) return;
  char line[160];
  const double t_s = static_cast<double>(t_ns / 1000U) * 1e-6;
  const int n = format_tum_line(line, sizeof line, t_s, pose);
  if (n > 0) std::fwrite(line, 1, static_cast<std::size_t>(n), file_);
}

bool TumWriter::close() {
  bool ok = true;
  if (file_ != nullptr) {
    ok = std::ferror(file_) == 0;
    ok = std::fclose(file_) == 0 && ok;
    file_ = nullptr;
  }
  delete[] buffer_;
  buffer_ = nullptr;
  return ok;
}

}  // namespace harmoloc::sim_host
