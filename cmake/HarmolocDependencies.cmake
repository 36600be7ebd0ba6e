# All dependencies come from Debian packages; `./run` installs them.
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
# Eigen as every harmoloc target uses it: with EIGEN_RUNTIME_NO_MALLOC everywhere, so that all
# translation units see the same inline Eigen functions, and a program can forbid Eigen's heap
# after start-up (the board mains do: firmware/eigen_guard.hpp). Allowed until switched off, so
# the trainer is unaffected.
add_library(harmoloc_eigen INTERFACE)
target_link_libraries(harmoloc_eigen INTERFACE Eigen3::Eigen)
target_compile_definitions(harmoloc_eigen INTERFACE EIGEN_RUNTIME_NO_MALLOC)
find_package(Threads REQUIRED)

# OpenCV core and imgproc only. Debian's libopencv-dev (the only package with OpenCVConfig.cmake)
# drags in every module and its arm64 flavour conflicts with amd64, so find the two libraries
# directly (docs/cross-build.md).
find_path(HARMOLOC_OPENCV_INCLUDE_DIR opencv2/core.hpp PATH_SUFFIXES opencv4)
find_library(HARMOLOC_OPENCV_CORE_LIB opencv_core)
find_library(HARMOLOC_OPENCV_IMGPROC_LIB opencv_imgproc)
if(HARMOLOC_OPENCV_INCLUDE_DIR AND HARMOLOC_OPENCV_CORE_LIB AND HARMOLOC_OPENCV_IMGPROC_LIB)
  add_library(harmoloc::opencv_core UNKNOWN IMPORTED)
  set_target_properties(harmoloc::opencv_core PROPERTIES
    IMPORTED_LOCATION ${HARMOLOC_OPENCV_CORE_LIB}
    INTERFACE_INCLUDE_DIRECTORIES ${HARMOLOC_OPENCV_INCLUDE_DIR})
  add_library(harmoloc::opencv_imgproc UNKNOWN IMPORTED)
  set_target_properties(harmoloc::opencv_imgproc PROPERTIES
    IMPORTED_LOCATION ${HARMOLOC_OPENCV_IMGPROC_LIB}
    INTERFACE_INCLUDE_DIRECTORIES ${HARMOLOC_OPENCV_INCLUDE_DIR}
    INTERFACE_LINK_LIBRARIES harmoloc::opencv_core)
  set(HARMOLOC_HAVE_OPENCV ON)
else()
  message(STATUS "OpenCV core/imgproc not found: the OpenCV reference checks are skipped")
  set(HARMOLOC_HAVE_OPENCV OFF)
endif()

find_package(tomlplusplus REQUIRED)

# SHA-256 for MAVLink 2 message signing: libnettle (Debian nettle-dev). Found directly, not with
# pkg-config, which the aarch64 cross build does not have.
find_path(HARMOLOC_NETTLE_INCLUDE_DIR nettle/sha2.h)
find_library(HARMOLOC_NETTLE_LIB nettle)
if(NOT HARMOLOC_NETTLE_INCLUDE_DIR OR NOT HARMOLOC_NETTLE_LIB)
  message(FATAL_ERROR "libnettle not found (Debian: apt-get install nettle-dev; ./run setup does it)")
endif()
add_library(harmoloc::nettle UNKNOWN IMPORTED)
set_target_properties(harmoloc::nettle PROPERTIES
  IMPORTED_LOCATION ${HARMOLOC_NETTLE_LIB}
  INTERFACE_INCLUDE_DIRECTORIES ${HARMOLOC_NETTLE_INCLUDE_DIR})

# Header-only (Debian packages of architecture all): the tools of every board.
find_package(CLI11 REQUIRED)
find_package(nlohmann_json 3 REQUIRED)

if(HARMOLOC_BUILD_TESTS)
  find_package(GTest REQUIRED)
  include(GoogleTest)
endif()

# Drivers' libraries, found directly (the aarch64 cross build has no pkg-config for them).
# libgpiod 1.6 (v1 API): Debian libgpiod-dev.
find_path(HARMOLOC_GPIOD_INCLUDE_DIR gpiod.h)
find_library(HARMOLOC_GPIOD_LIB gpiod)
if(HARMOLOC_GPIOD_INCLUDE_DIR AND HARMOLOC_GPIOD_LIB)
  add_library(harmoloc::gpiod UNKNOWN IMPORTED)
  set_target_properties(harmoloc::gpiod PROPERTIES
    IMPORTED_LOCATION ${HARMOLOC_GPIOD_LIB}
    INTERFACE_INCLUDE_DIRECTORIES ${HARMOLOC_GPIOD_INCLUDE_DIR})
  set(HARMOLOC_HAVE_GPIOD ON)
else()
  message(STATUS "libgpiod not found: the GPIO quadrature encoder driver is not built")
  set(HARMOLOC_HAVE_GPIOD OFF)
endif()
# libcamera 0.0.3: Debian libcamera-dev (headers under include/libcamera/libcamera).
find_path(HARMOLOC_LIBCAMERA_INCLUDE_DIR libcamera/libcamera.h PATH_SUFFIXES libcamera)
find_library(HARMOLOC_LIBCAMERA_LIB camera)
find_library(HARMOLOC_LIBCAMERA_BASE_LIB camera-base)
if(HARMOLOC_LIBCAMERA_INCLUDE_DIR AND HARMOLOC_LIBCAMERA_LIB AND HARMOLOC_LIBCAMERA_BASE_LIB)
  add_library(harmoloc::libcamera INTERFACE IMPORTED)
  set_target_properties(harmoloc::libcamera PROPERTIES
    INTERFACE_LINK_LIBRARIES "${HARMOLOC_LIBCAMERA_LIB};${HARMOLOC_LIBCAMERA_BASE_LIB}"
    INTERFACE_INCLUDE_DIRECTORIES ${HARMOLOC_LIBCAMERA_INCLUDE_DIR})
  set(HARMOLOC_HAVE_LIBCAMERA ON)
else()
  message(STATUS "libcamera not found: the libcamera driver is not built")
  set(HARMOLOC_HAVE_LIBCAMERA OFF)
endif()
