# SPDX-License-Identifier: MIT
# ISOKIT_FUZZ: every C++ source is instrumented for libFuzzer and built with ASan + UBSan (fuzz/,
# docs/fuzzing.md). Clang only; needs the apps (the rig loader and the setup parser live there).
if(ISOKIT_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "ISOKIT_FUZZ=ON needs clang (libFuzzer): configure with "
                        "-DCMAKE_CXX_COMPILER=clang++ (make fuzz does)")
  endif()
  if(NOT ISOKIT_APPS)
    message(FATAL_ERROR "ISOKIT_FUZZ=ON needs ISOKIT_APPS=ON (the rig loader is in apps/skinning)")
  endif()
  set(_fuzz_san -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all
                -fno-omit-frame-pointer -g)
  add_compile_options("$<$<COMPILE_LANGUAGE:CXX>:${_fuzz_san}>")
  add_link_options(-fsanitize=address,undefined)
endif()
