# SPDX-License-Identifier: MIT
# expect_png(path): fails the calling CTest script unless `path` exists and starts with the PNG
# signature. Included by the CLI test scripts.
function(expect_png path)
  if(NOT EXISTS "${path}")
    message(FATAL_ERROR "missing ${path}")
  endif()
  file(READ "${path}" magic LIMIT 4 HEX)
  if(NOT magic STREQUAL "89504e47")
    message(FATAL_ERROR "${path} is not a PNG")
  endif()
endfunction()
