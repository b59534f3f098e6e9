# SPDX-License-Identifier: MIT
# The python:install test: installs the isokit package (component python) into PREFIX and imports
# it from there with a clean environment (not from the build tree).
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${PREFIX} --component python
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install --component python failed (${rc})")
endif()
set(code "import isokit, os; assert isokit.__file__.startswith(os.environ['PYTHONPATH']), isokit.__file__; \
import isokit.operators, isokit.fields, isokit.tracker; print(isokit.__version__)")
execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=PYTHONHOME PYTHONPATH=${PREFIX}/${SITE} ${PYTHON} -c "${code}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "import isokit from ${PREFIX}/${SITE} failed: ${out}${err}")
endif()
file(GLOB stubs ${PREFIX}/${SITE}/isokit/*.pyi)
list(LENGTH stubs n)
if(n LESS 4)
  message(FATAL_ERROR "the .pyi stubs were not installed (${n} found)")
endif()
message(STATUS "isokit ${out} imported from ${PREFIX}/${SITE}")
