# Warnings every harmoloc target gets. Third-party headers are included as SYSTEM and stay quiet.
add_library(harmoloc_warnings INTERFACE)
target_compile_options(harmoloc_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion -Wnon-virtual-dtor
  -Wold-style-cast -Wcast-align -Wnull-dereference -Wdouble-promotion)
