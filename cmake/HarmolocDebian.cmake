# What both Debian packages (the firmware, cmake/HarmolocPackaging.cmake; the host tools,
# cmake/HarmolocToolsPackaging.cmake) need to be lintian clean: the maintainer, the changelog and
# the copyright file under /usr/share/doc/PACKAGE, and a manual page for every program, made
# from the program's own --help by help2man so that it cannot drift from the binary.
include(GNUInstallDirs)

set(HARMOLOC_PACKAGING_DIR ${PROJECT_SOURCE_DIR}/packaging)
set(HARMOLOC_MAINTAINER "harmoloc maintainers <harmoloc@example.org>"
  CACHE STRING "Maintainer field of the Debian packages (name <email>)")
# A cross build cannot run its own programs (and the firmware links libcamera, which hangs under
# qemu-user): its manual pages come from a native build of the same board, whose programs have
# the same command lines: the cross presets point here at build/linux/bin, which the build
# preset linux-help makes (./run package), and the arm64 tools at build/host/bin.
set(HARMOLOC_HELP_BIN_DIR "" CACHE PATH
  "Cross builds: bin/ of a native build of the same board, whose --help makes the manual pages")

# Debian architecture of the target into OUT: from the toolchain's multiarch triplet, else the
# build machine's own.
function(harmoloc_deb_arch out)
  if(CMAKE_LIBRARY_ARCHITECTURE STREQUAL "aarch64-linux-gnu")
    set(arch arm64)
  elseif(CMAKE_LIBRARY_ARCHITECTURE STREQUAL "arm-linux-gnueabihf")
    set(arch armhf)
  else()
    execute_process(COMMAND dpkg --print-architecture OUTPUT_VARIABLE arch
      OUTPUT_STRIP_TRAILING_WHITESPACE)
  endif()
  set(${out} ${arch} PARENT_SCOPE)
endfunction()

# The changelog and copyright of PACKAGE; the changelog compressed reproducibly (gzip -n).
function(harmoloc_debian_docs package)
  set(doc /usr/share/doc/${package})
  set(out ${PROJECT_BINARY_DIR}/debian-docs)
  file(MAKE_DIRECTORY ${out})
  configure_file(${HARMOLOC_PACKAGING_DIR}/changelog ${out}/changelog COPYONLY)
  execute_process(COMMAND gzip -9nf ${out}/changelog RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "gzip failed on ${out}/changelog")
  endif()
  install(FILES ${out}/changelog.gz DESTINATION ${doc})
  install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${doc} RENAME copyright)
endfunction()

# harmoloc_man_pages(NAME1 "one-line description" NAME2 "..." ...): man1 pages of the named
# programs (targets of this build), made by the target `man-pages` (./run package builds it
# before cpack) and installed with the package.
function(harmoloc_man_pages)
  find_program(HARMOLOC_HELP2MAN help2man)
  set(out ${PROJECT_BINARY_DIR}/man)
  set(pages)
  list(LENGTH ARGN n)
  math(EXPR last "${n} - 1")
  foreach(i RANGE 0 ${last} 2)
    math(EXPR j "${i} + 1")
    list(GET ARGN ${i} program)
    list(GET ARGN ${j} description)
    if(NOT TARGET ${program})
      continue()
    endif()
    if(CMAKE_CROSSCOMPILING)
      if(HARMOLOC_HELP_BIN_DIR STREQUAL "")
        continue()
      endif()
      set(exe ${HARMOLOC_HELP_BIN_DIR}/${program})
      set(depends ${exe})
    else()
      set(exe $<TARGET_FILE:${program}>)
      set(depends ${program})
    endif()
    add_custom_command(OUTPUT ${out}/${program}.1.gz
      COMMAND ${CMAKE_COMMAND} -E make_directory ${out}
      COMMAND ${HARMOLOC_HELP2MAN} --no-info --no-discard-stderr --name ${description}
              --output ${out}/${program}.1 ${exe}
      COMMAND gzip -9nf ${out}/${program}.1
      DEPENDS ${depends}
      COMMENT "manual page of ${program} (help2man)" VERBATIM)
    list(APPEND pages ${out}/${program}.1.gz)
  endforeach()
  add_custom_target(man-pages DEPENDS ${pages})
  if(pages)
    # OPTIONAL: a plain `cmake --install` need not have built them; the package checks do.
    install(FILES ${pages} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 OPTIONAL)
  endif()
endfunction()

# Debian's wrapping rule for the long description: lines of at most 80 columns (lintian).
function(harmoloc_check_description text)
  string(REPLACE "\n" ";" lines "${text}")
  foreach(line IN LISTS lines)
    string(LENGTH "${line}" len)
    if(len GREATER 79)
      message(FATAL_ERROR "package description line over 79 columns: ${line}")
    endif()
  endforeach()
endfunction()
