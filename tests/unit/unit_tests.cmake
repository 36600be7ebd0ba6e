# Unit tests (GoogleTest), one executable per area; label unit (ctest -L unit), the drivers'
# tests label drivers. Included from tests/CMakeLists.txt after
# enable_testing(), find_package(GTest) and include(GoogleTest); CMAKE_CURRENT_SOURCE_DIR is tests/.
set(HARMOLOC_UNIT_DIR ${CMAKE_CURRENT_SOURCE_DIR}/unit)

# algorithms/: segmentation, harmonic localizer and its training, odometry, particle filter,
# CAN layout, map codec.
add_executable(algorithms_test
  ${HARMOLOC_UNIT_DIR}/segmentation_test.cpp
  ${HARMOLOC_UNIT_DIR}/harmonic_test.cpp
  ${HARMOLOC_UNIT_DIR}/fix_board_check_test.cpp
  ${HARMOLOC_UNIT_DIR}/harmonic_selection_test.cpp
  ${HARMOLOC_UNIT_DIR}/route_placement_test.cpp
  ${HARMOLOC_UNIT_DIR}/odometry_calibration_test.cpp
  ${HARMOLOC_UNIT_DIR}/kernel_selection_test.cpp
  ${HARMOLOC_UNIT_DIR}/local_fix_error_test.cpp
  ${HARMOLOC_UNIT_DIR}/fix_error_grid_test.cpp
  ${HARMOLOC_UNIT_DIR}/forward_map_test.cpp
  ${HARMOLOC_UNIT_DIR}/bearing_calibration_test.cpp
  ${HARMOLOC_UNIT_DIR}/column_gain_test.cpp
  ${HARMOLOC_UNIT_DIR}/odometry_test.cpp
  ${HARMOLOC_UNIT_DIR}/particle_filter_test.cpp
  ${HARMOLOC_UNIT_DIR}/robust_filter_test.cpp
  ${HARMOLOC_UNIT_DIR}/projected_outline_test.cpp
  ${HARMOLOC_UNIT_DIR}/visibility_test.cpp
  ${HARMOLOC_UNIT_DIR}/floor_search_test.cpp
  ${HARMOLOC_UNIT_DIR}/frame_information_test.cpp
  ${HARMOLOC_UNIT_DIR}/nearby_pose_test_test.cpp
  ${HARMOLOC_UNIT_DIR}/can_layout_test.cpp
  ${HARMOLOC_UNIT_DIR}/map_codec_test.cpp)
target_link_libraries(algorithms_test PRIVATE harmoloc_algorithms harmoloc_training GTest::gtest_main
  harmoloc_warnings)
gtest_discover_tests(algorithms_test DISCOVERY_TIMEOUT 60 PROPERTIES LABELS unit)

# firmware/: configuration, MAVLink framing, the link's inbound side and its commands, latency
# histogram, map loading.
add_executable(firmware_test
  ${HARMOLOC_UNIT_DIR}/config_test.cpp
  ${HARMOLOC_UNIT_DIR}/cycle_pacer_test.cpp
  ${HARMOLOC_UNIT_DIR}/mavlink_test.cpp
  ${HARMOLOC_UNIT_DIR}/mavlink_inbound_test.cpp
  ${HARMOLOC_UNIT_DIR}/mavlink_commands_test.cpp
  ${HARMOLOC_UNIT_DIR}/cycle_startup_test.cpp
  ${HARMOLOC_UNIT_DIR}/cycle_fix_term_test.cpp
  ${HARMOLOC_UNIT_DIR}/cycle_cut_board_test.cpp
  ${HARMOLOC_UNIT_DIR}/mavlink_config_test.cpp
  ${HARMOLOC_UNIT_DIR}/pose_messages_test.cpp
  ${HARMOLOC_UNIT_DIR}/latency_histogram_test.cpp
  ${HARMOLOC_UNIT_DIR}/latency_window_test.cpp
  ${HARMOLOC_UNIT_DIR}/map_loader_test.cpp
  ${HARMOLOC_UNIT_DIR}/device_config_test.cpp
  ${HARMOLOC_UNIT_DIR}/health_log_test.cpp
  ${HARMOLOC_UNIT_DIR}/stats_dumper_test.cpp)
target_link_libraries(firmware_test PRIVATE harmoloc_firmware harmoloc_config harmoloc_algorithms
  harmoloc_board_common harmoloc_drivers_common harmoloc::nettle GTest::gtest_main harmoloc_warnings)
if(CMAKE_CROSSCOMPILING)
  target_compile_definitions(firmware_test PRIVATE HARMOLOC_TESTS_UNDER_QEMU_USER)
endif()
gtest_discover_tests(firmware_test DISCOVERY_TIMEOUT 60 PROPERTIES LABELS unit)

# drivers/ without devices: quadrature decoding, sequence gaps, V4L2 format negotiation, the SPSC
# ring, SocketCAN frame handling, the serial link's raw mode. Nothing here links libcamera, so it
# runs under qemu-aarch64 too. The devices themselves are tested in the VM (tests/vm/).
add_executable(drivers_test ${HARMOLOC_UNIT_DIR}/drivers_test.cpp
  ${HARMOLOC_UNIT_DIR}/input_file_test.cpp ${HARMOLOC_UNIT_DIR}/record_file_test.cpp
  ${HARMOLOC_UNIT_DIR}/frame_recorder_test.cpp
  ${HARMOLOC_UNIT_DIR}/service_notifier_test.cpp)
target_link_libraries(drivers_test PRIVATE harmoloc_drivers_can harmoloc_drivers_v4l2
  harmoloc_drivers_common harmoloc_input_files harmoloc_algorithms GTest::gtest_main
  harmoloc_warnings)
target_compile_definitions(drivers_test PRIVATE HARMOLOC_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
if(CMAKE_CROSSCOMPILING)
  target_compile_definitions(drivers_test PRIVATE HARMOLOC_TESTS_UNDER_QEMU_USER)
endif()
gtest_discover_tests(drivers_test DISCOVERY_TIMEOUT 60 PROPERTIES LABELS drivers)

# ThreadSanitizer's own negative control, in the host-tsan build only (the preset builds just the
# drivers' tests and this): a deliberate data race that TSan must report.
if(CMAKE_CXX_FLAGS MATCHES "sanitize=thread")
  add_executable(tsan_canary ${HARMOLOC_UNIT_DIR}/tsan_canary.cpp)
  target_link_libraries(tsan_canary PRIVATE Threads::Threads)
  add_test(NAME tsan.canary_reports_a_race COMMAND tsan_canary)
  set_tests_properties(tsan.canary_reports_a_race PROPERTIES LABELS tsan
    PASS_REGULAR_EXPRESSION "ThreadSanitizer: data race")
endif()

# The rest needs the host board (sim_host/, OpenCV): not built for the Linux boards.
if(NOT HARMOLOC_BOARD STREQUAL "host")
  return()
endif()

# sim_host/ and drivers/: dataset formats, the file-backed fakes, the simulator, the serial link.
add_executable(sim_host_test
  ${HARMOLOC_UNIT_DIR}/area_log_test.cpp
  ${HARMOLOC_UNIT_DIR}/board_projection_test.cpp
  ${HARMOLOC_UNIT_DIR}/geometry_fit_test.cpp
  ${HARMOLOC_UNIT_DIR}/dataset_test.cpp
  ${HARMOLOC_UNIT_DIR}/fakes_test.cpp
  ${HARMOLOC_UNIT_DIR}/forward_map_geometry_test.cpp
  ${HARMOLOC_UNIT_DIR}/forward_map_training_test.cpp
  ${HARMOLOC_UNIT_DIR}/label_offset_test.cpp
  ${HARMOLOC_UNIT_DIR}/random_scene_test.cpp
  ${HARMOLOC_UNIT_DIR}/recording_replay_test.cpp
  ${HARMOLOC_UNIT_DIR}/simulator_test.cpp
  ${HARMOLOC_UNIT_DIR}/toml_writer_test.cpp)
target_link_libraries(sim_host_test PRIVATE harmoloc_dataset harmoloc_drivers_host harmoloc_simulator
  harmoloc_trainer harmoloc_config
  harmoloc_drivers_common harmoloc_algorithms GTest::gtest_main harmoloc_warnings)
gtest_discover_tests(sim_host_test DISCOVERY_TIMEOUT 60 PROPERTIES LABELS unit)

# harmoloc-colours' library: windows, clustering, guided mode, warnings, TOML, and the automatic
# mode on three random simulated scenes against their true windows (about 20 s).
add_executable(colour_windows_test ${HARMOLOC_UNIT_DIR}/colour_windows_test.cpp)
target_link_libraries(colour_windows_test PRIVATE harmoloc_colours harmoloc_simulator
  harmoloc_config GTest::gtest_main harmoloc_warnings)
gtest_discover_tests(colour_windows_test DISCOVERY_TIMEOUT 60 PROPERTIES LABELS unit)

# Segmentation against OpenCV itself: HSV of all 2^24 colours, board classes, simulated and
# adversarial frames, YUYV. harmoloc_opencv_reference is defined in tests/CMakeLists.txt after
# this file is included, so the condition is the one that defines it (HARMOLOC_HAVE_OPENCV):
# `if(TARGET harmoloc_opencv_reference)` would still be false here.
if(TARGET harmoloc_opencv_reference OR HARMOLOC_HAVE_OPENCV)
  add_executable(segmentation_opencv_test ${HARMOLOC_UNIT_DIR}/segmentation_opencv_test.cpp)
  target_link_libraries(segmentation_opencv_test PRIVATE harmoloc_opencv_reference
    harmoloc_algorithms harmoloc_simulator GTest::gtest_main harmoloc_warnings)
  gtest_discover_tests(segmentation_opencv_test DISCOVERY_TIMEOUT 60 PROPERTIES LABELS unit)
endif()
