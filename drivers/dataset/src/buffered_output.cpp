#include "harmoloc/dataset/buffered_output.hpp"

#include <cerrno>

namespace harmoloc::dataset {

bool BufferedOutput::open(const std::string& path) {
  close();
  error_ = 0;
  path_ = path;
  file_ = std::fopen(path.c_str(), "w");
  if (file_ == nullptr) return false;
  buffer_ = new char[kBufferBytes];
  std::setvbuf(file_, buffer_, _IOFBF, kBufferBytes);
  return true;
}

void BufferedOutput::append(const char* bytes, std::size_t size) {
  if (file_ == nullptr) return;
  errno = 0;
  if (std::fwrite(bytes, 1, size, file_) != size && error_ == 0) error_ = errno != 0 ? errno : EIO;
}

bool BufferedOutput::close() {
  bool ok = true;
  if (file_ != nullptr) {
    errno = 0;
    ok = std::ferror(file_) == 0;
    ok = std::fclose(file_) == 0 && ok;
    if (!ok && error_ == 0) error_ = errno != 0 ? errno : EIO;
    ok = ok && error_ == 0;
    file_ = nullptr;
  }
  delete[] buffer_;
  buffer_ = nullptr;
  return ok;
}

}  // namespace harmoloc::dataset
