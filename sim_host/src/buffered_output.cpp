#include "harmoloc/sim_host/buffered_output.hpp"

namespace harmoloc::sim_host {

bool BufferedOutput::open(const std::string& path) {
  close();
  file_ = std::fopen(path.c_str(), "w");
  if (file_ == nullptr) return false;
  buffer_ = new char[kBufferBytes];
  std::setvbuf(file_, buffer_, _IOFBF, kBufferBytes);
  return true;
}

void BufferedOutput::append(const char* bytes, std::size_t size) {
  if (file_ != nullptr) std::fwrite(bytes, 1, size, file_);
}

bool BufferedOutput::close() {
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
