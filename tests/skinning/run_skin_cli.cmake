# isokit-skin end to end (CTest skin:cli). Checks files and JSON contents, not pictures.
file(REMOVE_RECURSE "${OUT}")
function(run)
  execute_process(COMMAND "${EXE}" ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "isokit-skin ${ARGN} failed (${rc}):\n${out}\n${err}")
  endif()
  set(LAST_OUT "${out}" PARENT_SCOPE)
  set(LAST_ERR "${err}" PARENT_SCOPE)
endfunction()
include(${CMAKE_CURRENT_LIST_DIR}/../png_check.cmake)

# info on a procedural rig lists its joints.
run(info "procedural:finger?vertices=1500")
if(NOT LAST_OUT MATCHES "Finger3")
  message(FATAL_ERROR "info does not list the joints:\n${LAST_OUT}")
endif()

# info --fit reports every joint's primitive.
run(info "procedural:finger?vertices=1500" --fit)
if(NOT LAST_OUT MATCHES "primitives: 4 of 4" OR NOT LAST_OUT MATCHES "related / unrelated")
  message(FATAL_ERROR "info --fit does not report the primitives:\n${LAST_OUT}")
endif()

# A rig whose parts the mesh under-resolves gets a warning (and still bakes).
run(bake "procedural:cylinder?vertices=80" --method tracking2014 --bend Bone1:z:90 --frames 5
    --out "${OUT}/coarse/out.glb")
if(NOT LAST_ERR MATCHES "under-resolves" OR NOT EXISTS "${OUT}/coarse/out.glb")
  message(FATAL_ERROR "no under-resolved warning for an 80-vertex cylinder:\n${LAST_ERR}")
endif()
run(bake procedural:cylinder --method dqs --bend Bone1:z:90 --frames 5 --out "${OUT}/fine/out.glb")
if(LAST_ERR MATCHES "under-resolves")
  message(FATAL_ERROR "under-resolved warning on the 2,000-vertex cylinder:\n${LAST_ERR}")
endif()

# bake with every output on the cylinder.
run(bake procedural:cylinder --method tracking2014 --bend Bone1:x:120 --frames 9 --compare
    --out "${OUT}/cyl/out.glb" --metrics "${OUT}/cyl/metrics.json" --render "${OUT}/cyl/render"
    --ply "${OUT}/cyl/ply" --pc2 "${OUT}/cyl/out.pc2")
foreach(f cyl/out.glb cyl/metrics.json cyl/ply/frame_0000.ply cyl/ply/frame_0008.ply cyl/out.pc2)
  if(NOT EXISTS "${OUT}/${f}")
    message(FATAL_ERROR "bake did not write ${f}")
  endif()
endforeach()
# The point cache: signature, then 9 samples of every vertex (header 32 bytes, 12 per point).
file(READ "${OUT}/cyl/out.pc2" pc2_head LIMIT 12 HEX)
file(SIZE "${OUT}/cyl/out.pc2" pc2_size)
math(EXPR pc2_points "(${pc2_size} - 32) / 108")
math(EXPR pc2_rest "(${pc2_size} - 32) % 108")
if(NOT pc2_head STREQUAL "504f494e5443414348453200" OR NOT pc2_rest EQUAL 0 OR pc2_points LESS 1000)
  message(FATAL_ERROR "out.pc2 is not a PC2 cache of 9 frames (${pc2_head}, ${pc2_size} bytes)")
endif()
# Read back: the cylinder's file order is its welded order, so sample k of the cache holds the
# same float32 bytes as the vertex block of frame k's PLY.
foreach(k 0 4 8)
  file(READ "${OUT}/cyl/ply/frame_000${k}.ply" ply_head LIMIT 400)
  string(FIND "${ply_head}" "end_header\n" at)
  string(REGEX MATCH "element vertex ([0-9]+)" _ "${ply_head}")
  set(nv ${CMAKE_MATCH_1})
  math(EXPR at "${at} + 11")
  math(EXPR block "${nv} * 12")
  math(EXPR pc2_at "32 + ${k} * ${block}")
  file(READ "${OUT}/cyl/ply/frame_000${k}.ply" ply_xyz OFFSET ${at} LIMIT ${block} HEX)
  file(READ "${OUT}/cyl/out.pc2" pc2_xyz OFFSET ${pc2_at} LIMIT ${block} HEX)
  if(NOT nv EQUAL pc2_points OR NOT ply_xyz STREQUAL pc2_xyz)
    message(FATAL_ERROR "out.pc2 sample ${k} differs from frame_000${k}.ply (${nv} / ${pc2_points} points)")
  endif()
endforeach()
expect_png("${OUT}/cyl/render/contact_sheet.png")
file(READ "${OUT}/cyl/out.glb" magic LIMIT 4 HEX)
if(NOT magic STREQUAL "676c5446")
  message(FATAL_ERROR "out.glb is not a binary glTF")
endif()
file(READ "${OUT}/cyl/metrics.json" json)
foreach(m lbs dqs implicit2013 tracking2014)
  string(JSON n LENGTH "${json}" methods ${m} frames)
  if(NOT n EQUAL 9)
    message(FATAL_ERROR "metrics.json: ${m} has ${n} frames, expected 9")
  endif()
endforeach()
string(JSON inv GET "${json}" methods tracking2014 worst new_inverted_triangles)
string(JSON rec GET "${json}" methods tracking2014 rest_recovery)
message(STATUS "cylinder 120 deg tracking2014: new inverted ${inv}, rest recovery ${rec}")

# demo on a small humanoid: every output of `make demo`.
run(demo --out "${OUT}/demo" --vertices 4000 --frames 7)
expect_png("${OUT}/demo/contact_sheet.png")
foreach(f implicit2013.glb metrics.json)  # the default method's bake
  if(NOT EXISTS "${OUT}/demo/${f}")
    message(FATAL_ERROR "demo did not write ${f}")
  endif()
endforeach()
if(NOT LAST_OUT MATCHES "tracking2014" OR NOT LAST_OUT MATCHES "implicit2013")
  message(FATAL_ERROR "demo did not print its table:\n${LAST_OUT}")
endif()

# Bad input: clear message, exit code 2, no output file.
foreach(args "bake;procedural:cylinder;--bend;Elbow:x:90;--out;${OUT}/bad.glb"
             "bake;procedural:nothing;--bend;Bone1:x:90;--out;${OUT}/bad.glb"
             "bake;${OUT}/missing.glb;--bend;0:x:90;--out;${OUT}/bad.glb"
             "bake;procedural:cylinder;--bend;Bone1:x:90;--method;magic;--out;${OUT}/bad.glb"
             "bake;procedural:cylinder;--bend;Bone1:x:90;--max-step-rad;-1;--out;${OUT}/bad.glb"
             "bake;procedural:cylinder;--bend;Bone1:x:90;--max-step-rad;abc;--out;${OUT}/bad.glb"
             "bake;procedural:cylinder;--bend;Bone1:x:90;--fps;0;--out;${OUT}/bad.glb"
             "bake;procedural:cylinder;--bend;Bone1:x:90;--frames;2;--out;${OUT}/bad.glb"
             "bake;procedural:cylinder;--out;${OUT}/bad.glb"
             "bake;procedural:cylinder;--bend;Bone1:x:90;--device;cuda;--out;${OUT}/bad.glb"
             "bake;procedural:cylinder;--bend;Bone1:x:90;--device;tpu;--out;${OUT}/bad.glb"
             "bake;procedural:cylinder;--method;dqs;--bend;Bone1:x:90;--frames;3;--out;${OUT}/bad.glb;--pc2;${OUT}/bad.txt"
             "demo;--out;${OUT}/bad;--vertices;-5")
  execute_process(COMMAND "${EXE}" ${args} RESULT_VARIABLE rc OUTPUT_VARIABLE o ERROR_VARIABLE e)
  if(NOT rc EQUAL 2 OR NOT e MATCHES "error")
    message(FATAL_ERROR "isokit-skin ${args}: expected exit 2 with an error message, got ${rc}:\n${e}")
  endif()
  # One line: the message after the progress lines has no line break of its own.
  string(REGEX REPLACE "^.*error: " "" last "${e}")
  string(STRIP "${last}" last)
  if(last MATCHES "\n")
    message(FATAL_ERROR "isokit-skin ${args}: the error is not one line:\n${e}")
  endif()
  if(EXISTS "${OUT}/bad.glb")
    message(FATAL_ERROR "isokit-skin ${args} wrote an output despite the error")
  endif()
endforeach()
