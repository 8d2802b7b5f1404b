# Project-wide compile flags, applied through an interface target so that
# third-party code (GoogleTest, Boost) is not held to our warning level.
add_library(canopen_options INTERFACE)
target_compile_options(canopen_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast
  -Wcast-align -Wconversion -Wdouble-promotion
  -Wformat=2 -Wimplicit-fallthrough -Wmisleading-indentation)
if(CANOPEN_WERROR)
  target_compile_options(canopen_options INTERFACE -Werror)
endif()
if(CANOPEN_SANITIZE)
  target_compile_options(canopen_options INTERFACE
    -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(canopen_options INTERFACE -fsanitize=address,undefined)
endif()
if(CANOPEN_FUZZ)
  # Coverage instrumentation for the libraries; fuzz executables add -fsanitize=fuzzer.
  target_compile_options(canopen_options INTERFACE -fsanitize=fuzzer-no-link)
endif()
