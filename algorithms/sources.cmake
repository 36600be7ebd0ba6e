# The sources of algorithms/, in one place for every build that compiles them: the host and Linux
# boards (algorithms/CMakeLists.txt) and the bare-metal kernels (tests/baremetal/CMakeLists.txt).
# Paths relative to algorithms/.

# The online half: what the cycle runs. No I/O, no OS calls, no heap.
set(HARMOLOC_ALGORITHMS_SOURCES
  src/can_encoder_layout.cpp
  src/column_gain.cpp
  src/crc32.cpp
  src/harmonic_localizer.cpp
  src/harmonic_model.cpp
  src/map_codec_read.cpp
  src/map_codec_read_forward.cpp
  src/map_codec_write.cpp
  src/odometry.cpp
  src/board_observation.cpp
  src/floor_search.cpp
  src/nearby_pose_test.cpp
  src/forward_map.cpp
  src/projected_bearing.cpp
  src/fix_board_check.cpp
  src/fix_error_grid.cpp
  src/kidnap_detector.cpp
  src/particle_filter.cpp
  src/segmentation.cpp
  src/segmentation_avx2.cpp   # empty unless x86-64 (AVX2 by function attribute, chosen at run time)
  src/segmentation_neon.cpp)  # empty unless the target has NEON

# The offline half of the harmonic localizer (eq. 8, model and kernel selection, placing frames
# by odometry): Eigen, dynamic sizes, host only.
set(HARMOLOC_TRAINING_SOURCES
  src/harmonic_training.cpp
  src/harmonic_selection.cpp
  src/route_placement.cpp
  src/odometry_calibration.cpp
  src/kernel_selection.cpp
  src/local_fix_error.cpp
  src/bearing_calibration.cpp
  # The information a frame holds about the pose: the sweep's traces write it (not the cycle).
  src/frame_information.cpp)
