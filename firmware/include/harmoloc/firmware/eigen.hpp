#pragma once
/// @file Eigen for firmware code: include this instead of <Eigen/...> (before any Eigen
/// header). eigen_assert is on in every build type (Eigen's own is off with NDEBUG), so that
/// EIGEN_RUNTIME_NO_MALLOC's check fires in the release firmware too: after
/// forbid_eigen_heap(), an allocating Eigen object aborts with one line (eigen_guard.hpp).

#include "harmoloc/firmware/eigen_guard.hpp"

#ifndef EIGEN_RUNTIME_NO_MALLOC
#error "firmware code must be built with EIGEN_RUNTIME_NO_MALLOC (link harmoloc_eigen)"
#endif
#ifdef EIGEN_CORE_H
#error "include harmoloc/firmware/eigen.hpp before any Eigen header"
#endif

#define eigen_assert(x)                                                                           \
  do {                                                                                            \
    if (!static_cast<bool>(x)) ::harmoloc::firmware::eigen_assert_failed(#x, __FILE__, __LINE__); \
  } while (false)

#include <Eigen/Core>
