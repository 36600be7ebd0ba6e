# Install rules and the Debian package of a Linux board build (docs/deploy.md): the firmware, the
# tools a robot needs, a default config and a systemd unit. `./run package` builds one .deb per
# target architecture into build/packages/; tests/packaging/check_package.sh checks them.
include(HarmolocDebian)

# The firmware itself: the Linux board's executable, once that board has one.
if(TARGET harmoloc)
  install(TARGETS harmoloc RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
# Tools for the robot: the budget table of the stats the firmware writes, and the link monitor.
if(TARGET harmoloc-budget)
  install(TARGETS harmoloc-budget RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
if(TARGET harmoloc-monitor)
  install(TARGETS harmoloc-monitor RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

# Configuration (conffiles: dpkg keeps local changes on upgrade). The default config is the
# documented example, which the tests check to reproduce the built-in defaults.
install(FILES ${PROJECT_SOURCE_DIR}/docs/examples/harmoloc.toml DESTINATION /etc/harmoloc)
install(FILES ${HARMOLOC_PACKAGING_DIR}/harmoloc.default DESTINATION /etc/default RENAME harmoloc)
install(FILES ${HARMOLOC_PACKAGING_DIR}/harmoloc.service DESTINATION /lib/systemd/system)
install(FILES
  ${PROJECT_SOURCE_DIR}/docs/deploy.md
  ${PROJECT_SOURCE_DIR}/docs/config-format.md
  ${PROJECT_SOURCE_DIR}/docs/wire-protocol.md
  ${PROJECT_SOURCE_DIR}/docs/stats-format.md
  DESTINATION ${CMAKE_INSTALL_DOCDIR})
harmoloc_debian_docs(harmoloc)
harmoloc_man_pages(
  harmoloc "localize a mobile robot from a camera and its wheel encoders (the firmware)"
  harmoloc-budget "per-stage cycle time against the compute budget, from harmoloc's stats"
  harmoloc-monitor "show harmoloc's MAVLink pose stream and send it commands")

harmoloc_deb_arch(HARMOLOC_DEB_ARCH)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME harmoloc)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "${HARMOLOC_MAINTAINER}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "visual localization firmware for mobile robots (camera + wheel encoders)")
string(CONCAT CPACK_PACKAGE_DESCRIPTION
  "Localizes a mobile robot at 30 Hz from a monocular camera and its wheel\n"
  "encoders: board areas in the raw frame, a precomputed harmonic localizer and a\n"
  "particle filter. The pose goes out as MAVLink v2 on a serial line. Started at\n"
  "boot by harmoloc.service with real-time limits.")
harmoloc_check_description("${CPACK_PACKAGE_DESCRIPTION}")
set(CPACK_PACKAGE_FILE_NAME harmoloc_${PROJECT_VERSION}_${HARMOLOC_DEB_ARCH})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${HARMOLOC_DEB_ARCH})
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Shared-library dependencies from dpkg-shlibdeps, which reads the target architecture from the
# binaries and finds its libraries among the installed multiarch packages; passwd for the
# system user the package makes; init-system-helpers for deb-systemd-invoke in the maintainer
# scripts.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "passwd, init-system-helpers (>= 1.52)")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "can-utils")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(HARMOLOC_CONTROL_DIR ${PROJECT_BINARY_DIR}/debian-control)
file(WRITE ${HARMOLOC_CONTROL_DIR}/conffiles "/etc/harmoloc/harmoloc.toml\n/etc/default/harmoloc\n")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
  ${HARMOLOC_CONTROL_DIR}/conffiles
  ${HARMOLOC_PACKAGING_DIR}/postinst
  ${HARMOLOC_PACKAGING_DIR}/prerm
  ${HARMOLOC_PACKAGING_DIR}/postrm)
# Strip the binaries (the build tree keeps the symbols).
set(CPACK_STRIP_FILES ON)
include(CPack)
