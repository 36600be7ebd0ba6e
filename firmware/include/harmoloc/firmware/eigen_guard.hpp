#pragma once
/// @file Eigen's heap after start-up. Every harmoloc target that sees Eigen is built with
/// EIGEN_RUNTIME_NO_MALLOC (cmake: harmoloc_eigen), and firmware code includes Eigen only
/// through harmoloc/firmware/eigen.hpp, whose eigen_assert stays on in release builds. Once a
/// board main has called forbid_eigen_heap() (after start-up, before the first cycle), any
/// Eigen object that would allocate (a dynamic size) stops the program with one line naming
/// the place: a programming error the cycle must not contain. Fixed-size Eigen types never
/// allocate and stay usable. This header does not include Eigen.

namespace harmoloc::firmware {

/// Eigen may not allocate from here on (Eigen::internal::set_is_malloc_allowed(false)).
void forbid_eigen_heap();
/// Eigen may allocate again (tests; a tool that trains after running the cycle).
void allow_eigen_heap();
bool eigen_heap_allowed();

/// What eigen_assert calls in firmware code when its condition fails: one line on stderr, then
/// std::abort().
[[noreturn]] void eigen_assert_failed(const char* condition, const char* file, int line);

}  // namespace harmoloc::firmware
