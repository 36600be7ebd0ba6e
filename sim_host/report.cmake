# The run report: evaluation numbers, SVG plots and an HTML page from a replay run's outputs.
# Included from sim_host/CMakeLists.txt (CMAKE_CURRENT_SOURCE_DIR is sim_host/ there).
# Needs: harmoloc_dataset (tum.hpp/tum.cpp), harmoloc_warnings, nlohmann_json, CLI11;
# harmoloc_report_link also the firmware's MAVLink parser.
# src/report/: one file a job. harmoloc-budget uses only the stats model (run_stats); the SVG
# toolkit (svg*.cpp) serves both the report's plots and line_chart.cpp.
set(HARMOLOC_REPORT_SOURCES format.cpp svg.cpp svg_ticks.cpp svg_plot.cpp
  trajectory_evaluation.cpp run_stats.cpp report.cpp summary.cpp trajectory_plot.cpp
  trajectory_view.cpp error_plot.cpp timing_plot.cpp stages_plot.cpp page.cpp relative_error.cpp health_label.cpp
  time_panel.cpp xy_error_plot.cpp sigma_plot.cpp health_plot.cpp histogram_edges.cpp
  area_spans.cpp areas_plot.cpp compare_runs.cpp compare_plots.cpp compare_page.cpp)
list(TRANSFORM HARMOLOC_REPORT_SOURCES PREPEND ${CMAKE_CURRENT_SOURCE_DIR}/src/report/)
add_library(harmoloc_report STATIC ${HARMOLOC_REPORT_SOURCES}
  ${CMAKE_CURRENT_SOURCE_DIR}/src/line_chart.cpp)
add_library(harmoloc::report ALIAS harmoloc_report)
target_include_directories(harmoloc_report PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
target_link_libraries(harmoloc_report
  PUBLIC harmoloc_dataset harmoloc_stats_document nlohmann_json::nlohmann_json
  PRIVATE harmoloc_warnings)

# Reading a recorded link (health and spread over time) takes the firmware's MAVLink parser: a
# library of its own, so that harmoloc-budget (on the robot) and the other users of the report
# library do not link the firmware.
add_library(harmoloc_report_link STATIC ${CMAKE_CURRENT_SOURCE_DIR}/src/report/link_log.cpp)
target_link_libraries(harmoloc_report_link PUBLIC harmoloc_report
  PRIVATE harmoloc_firmware harmoloc_warnings)

add_executable(harmoloc-report ${CMAKE_CURRENT_SOURCE_DIR}/tools/harmoloc_report.cpp)
target_link_libraries(harmoloc-report PRIVATE harmoloc_report harmoloc_report_link harmoloc_cli
  harmoloc_warnings)
