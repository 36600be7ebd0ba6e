#include "harmoloc/firmware/eigen_guard.hpp"

#include <cstdio>
#include <cstdlib>

#include "harmoloc/firmware/eigen.hpp"

namespace harmoloc::firmware {

void forbid_eigen_heap() {
  Eigen::internal::set_is_malloc_allowed(false);
}

void allow_eigen_heap() {
  Eigen::internal::set_is_malloc_allowed(true);
}

bool eigen_heap_allowed() {
  return Eigen::internal::is_malloc_allowed();
}

void eigen_assert_failed(const char* condition, const char* file, int line) {
  std::fprintf(stderr, "harmoloc: Eigen: %s failed at %s:%d\n", condition, file, line);
  std::abort();
}

}  // namespace harmoloc::firmware
