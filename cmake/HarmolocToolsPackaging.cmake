# The Debian package of the host tools, harmoloc-tools (docs/deploy.md, "The laptop's tools"):
# what a robot owner runs beside the robot: the simulator, the colour tool, the trainer, the
# report, the sweep, the stats budget, the link monitor and the host board's replay
# (`harmoloc --dataset`). Built from the host build for this machine, and cross-built for arm64
# (preset tools-aarch64) so that a robot with an arm64 computer can train its own map;
# `./run package` puts both beside the firmware packages and
# tests/packaging/check_tools_package.sh checks them.
include(HarmolocDebian)

set(HARMOLOC_HOST_TOOLS harmoloc harmoloc-sim harmoloc-train harmoloc-report harmoloc-accuracy
  harmoloc-scenarios harmoloc-sweep harmoloc-colours harmoloc-budget harmoloc-monitor)
foreach(tool IN LISTS HARMOLOC_HOST_TOOLS)
  if(TARGET ${tool})
    install(TARGETS ${tool} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()
harmoloc_man_pages(
  harmoloc "replay a recorded run through the firmware's localization cycle (host board)"
  harmoloc-sim "simulate a robot's run, or a random scene, as a dataset folder"
  harmoloc-train "train a harmoloc map from a recorded run and labelled poses"
  harmoloc-report "evaluate a replayed run against ground truth as an HTML report"
  harmoloc-accuracy "the harmonic localizer's accuracy on simulated routes"
  harmoloc-scenarios "the particle filter's table of simulated scenarios"
  harmoloc-sweep "train and evaluate the estimator on many random scenes"
  harmoloc-colours "propose the boards' colour windows from a recording, with mask previews"
  harmoloc-budget "per-stage cycle time against the compute budget, from harmoloc's stats"
  harmoloc-monitor "show harmoloc's MAVLink pose stream and send it commands")

set(doc /usr/share/doc/harmoloc-tools)
install(FILES
  ${PROJECT_SOURCE_DIR}/README.md
  ${PROJECT_SOURCE_DIR}/docs/training.md
  ${PROJECT_SOURCE_DIR}/docs/colours.md
  ${PROJECT_SOURCE_DIR}/docs/dataset-format.md
  ${PROJECT_SOURCE_DIR}/docs/scenarios.md
  ${PROJECT_SOURCE_DIR}/docs/sweep.md
  ${PROJECT_SOURCE_DIR}/docs/config-format.md
  ${PROJECT_SOURCE_DIR}/docs/stats-format.md
  ${PROJECT_SOURCE_DIR}/docs/wire-protocol.md
  DESTINATION ${doc})
harmoloc_debian_docs(harmoloc-tools)

harmoloc_deb_arch(HARMOLOC_DEB_ARCH)
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME harmoloc-tools)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "${HARMOLOC_MAINTAINER}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "host tools of the harmoloc robot localization firmware")
string(CONCAT CPACK_PACKAGE_DESCRIPTION
  "What a robot owner runs on a laptop beside a robot that runs harmoloc: the\n"
  "scenario simulator, the map trainer, the replay of a recorded run through the\n"
  "firmware's cycle, the accuracy report, the sweep over random scenes, the\n"
  "stats budget and the MAVLink link monitor.")
harmoloc_check_description("${CPACK_PACKAGE_DESCRIPTION}")
set(CPACK_PACKAGE_FILE_NAME harmoloc-tools_${PROJECT_VERSION}_${HARMOLOC_DEB_ARCH})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${HARMOLOC_DEB_ARCH})
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# The firmware package installs harmoloc, harmoloc-budget and harmoloc-monitor of its board
# under the same names: a machine has one or the other.
set(CPACK_DEBIAN_PACKAGE_CONFLICTS "harmoloc")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_STRIP_FILES ON)
include(CPack)
