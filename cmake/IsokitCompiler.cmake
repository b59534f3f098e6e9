# SPDX-License-Identifier: MIT
# Warning and sanitizer settings for isokit's own targets.

# isokit_target_defaults(<target>): -Wall -Wextra (-Werror) on isokit's own C++ sources.
function(isokit_target_defaults target)
  set(flags -Wall -Wextra -Wpedantic -Wshadow)
  if(ISOKIT_WERROR)
    list(APPEND flags -Werror)
  endif()
  target_compile_options(${target} PRIVATE "$<$<COMPILE_LANGUAGE:CXX>:${flags}>")
endfunction()

if(ISOKIT_SANITIZE)
  set(_san -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_compile_options("$<$<COMPILE_LANGUAGE:CXX>:${_san}>")
  add_link_options(${_san})
endif()
