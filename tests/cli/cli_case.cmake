# One end-to-end case of the `btr` program, run by ctest:
#   cmake -DBTR=<program> -DINPUTS=<inputs dir> -DWORK=<scratch dir> -DCASE=<case>
#         [-DSCENE=<name in inputs/>] [-DCOUNT=<grains>] -P cli_case.cmake
# Cases: deterministic, check, missing_scene, unknown_key, shake_series, shake_without_table, drum_series,
# redeposit_series, redeposit_without_table. Fails with message(FATAL_ERROR).
cmake_minimum_required(VERSION 3.18)

# Runs the program; sets <prefix>_code and <prefix>_text (stdout + stderr).
function(run_btr prefix)
  execute_process(COMMAND ${BTR} ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(${prefix}_code "${code}" PARENT_SCOPE)
  set(${prefix}_text "${out}${err}" PARENT_SCOPE)
endfunction()

function(expect_code prefix expected)
  if(NOT "${${prefix}_code}" STREQUAL "${expected}")
    message(FATAL_ERROR "btr exited with '${${prefix}_code}', expected ${expected}. Output:\n${${prefix}_text}")
  endif()
endfunction()

function(expect_mentions prefix needle)
  string(FIND "${${prefix}_text}" "${needle}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the message does not mention '${needle}':\n${${prefix}_text}")
  endif()
endfunction()

# Two runs of a series command, in WORK/a and WORK/b: the snapshots NAME_<tag>NNNNNN.{csv,vtp} (at least
# min_files of them) byte-identical, and the per-step table NAME_<table>.csv identical once `regex` ->
# `replace` has blanked its timing columns, with `rows` lines.
function(expect_identical_series tag min_files table regex replace rows)
  file(GLOB snaps RELATIVE "${WORK}/a" "${WORK}/a/${SCENE}_${tag}[0-9]*.csv" "${WORK}/a/${SCENE}_${tag}[0-9]*.vtp")
  list(LENGTH snaps n_snaps)
  if(n_snaps LESS min_files)
    message(FATAL_ERROR "expected at least ${min_files} snapshot files (CSV + VTP), got: ${snaps}")
  endif()
  foreach(f ${snaps})
    execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${WORK}/a/${f}" "${WORK}/b/${f}" RESULT_VARIABLE same)
    if(NOT same EQUAL 0)
      message(FATAL_ERROR "${f} differs between two runs with the same seed")
    endif()
  endforeach()
  foreach(run a b)
    file(STRINGS "${WORK}/${run}/${SCENE}_${table}.csv" lines)
    set(stripped_${run} "")
    foreach(line ${lines})
      string(REGEX REPLACE "${regex}" "${replace}" line "${line}")
      list(APPEND stripped_${run} "${line}")
    endforeach()
  endforeach()
  list(LENGTH stripped_a n_rows)
  if(NOT n_rows EQUAL rows)
    message(FATAL_ERROR "expected ${rows} lines (a header and the rows) in ${SCENE}_${table}.csv, got ${n_rows}")
  endif()
  if(NOT "${stripped_a}" STREQUAL "${stripped_b}")
    message(FATAL_ERROR "${SCENE}_${table}.csv differs between two runs with the same seed")
  endif()
endfunction()

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
set(scene "${INPUTS}/${SCENE}.toml")

if(CASE STREQUAL "deterministic")
  # Same seed twice: byte-identical CSV files. Another seed: different ones.
  foreach(run a b c)
    set(seed 7)
    if(run STREQUAL "c")
      set(seed 8)
    endif()
    run_btr(r deposit "${scene}" -o "${WORK}/${run}" --seed ${seed} --count ${COUNT} --quiet)
    expect_code(r 0)
  endforeach()
  file(GLOB csvs RELATIVE "${WORK}/a" "${WORK}/a/*.csv")
  if(NOT csvs)
    message(FATAL_ERROR "no CSV file written in ${WORK}/a")
  endif()
  foreach(csv ${csvs})
    file(STRINGS "${WORK}/a/${csv}" lines)
    list(LENGTH lines n)
    list(GET lines 0 header)
    math(EXPR expected_lines "${COUNT} + 1")
    if(NOT header STREQUAL "id,x,y,z,radius,species" OR NOT n EQUAL expected_lines)
      message(FATAL_ERROR "${csv}: header '${header}' and ${n} lines, expected the packing header and ${expected_lines} lines")
    endif()
    execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${WORK}/a/${csv}" "${WORK}/b/${csv}" RESULT_VARIABLE same)
    if(NOT same EQUAL 0)
      message(FATAL_ERROR "${csv} differs between two runs with the same seed")
    endif()
    execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${WORK}/a/${csv}" "${WORK}/c/${csv}" RESULT_VARIABLE same)
    if(same EQUAL 0)
      message(FATAL_ERROR "${csv} is identical for seeds 7 and 8")
    endif()
  endforeach()

elseif(CASE STREQUAL "check")
  run_btr(r deposit "${scene}" -o "${WORK}/out" --check --quiet)
  expect_code(r 0)

elseif(CASE STREQUAL "bench_scenes")
  # The bench's three default scenes at toy sizes: a row each, the exponents and the depth ratio.
  run_btr(r bench --sizes 300,600 --drum-sizes 150,300 --drum-steps 2)
  expect_code(r 0)
  foreach(needle "bed3d           300        300" "bed3d_deep      600        600" "drum3d          300        600"
                 "B/grain" "exponent"
                 "10x deeper bed / shallow bed" "N = 600")
    expect_mentions(r "${needle}")
  endforeach()
  run_btr(bad bench --drum-steps 0)
  expect_code(bad 2)
  expect_mentions(bad "--drum-steps")

elseif(CASE STREQUAL "missing_scene")
  run_btr(r deposit "${WORK}/no_such_scene.toml" -o "${WORK}/out")
  expect_code(r 2)
  expect_mentions(r "no_such_scene.toml")

elseif(CASE STREQUAL "unknown_key")
  file(READ "${scene}" text)
  string(REPLACE "[scene]\n" "[scene]\ntypo_key = 1\n" text "${text}")
  file(WRITE "${WORK}/typo_scene.toml" "${text}")
  run_btr(r deposit "${WORK}/typo_scene.toml" -o "${WORK}/out")
  expect_code(r 2)
  expect_mentions(r "typo_scene.toml")
  expect_mentions(r "typo_key")

elseif(CASE STREQUAL "shake_series")
  # Dynamic BTR: same scene and seed twice give byte-identical snapshots (CSV, VTP) and per-cycle
  # tables (less the wall-time column); every snapshot passes --check; the .pvd lists every snapshot.
  foreach(run a b)
    run_btr(r shake "${scene}" -o "${WORK}/${run}" --cycles 4 --check --quiet)
    expect_code(r 0)
  endforeach()
  expect_identical_series(c 4 cycles "^([^,]*),[^,]*," "\\1,," 6)  # cycles 0 and 4; header + cycles 0..4
  file(READ "${WORK}/a/${SCENE}.pvd" pvd)
  foreach(c 000000 000004)
    string(FIND "${pvd}" "file=\"${SCENE}_c${c}.vtp\"" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "${SCENE}.pvd does not list ${SCENE}_c${c}.vtp:\n${pvd}")
    endif()
  endforeach()

elseif(CASE STREQUAL "drum_series")
  # Rotating drum: same scene and seed twice give byte-identical snapshots and step tables (less the
  # wall-time and CPU-time columns); every snapshot passes --check; the .pvd lists the snapshots with their angle.
  foreach(run a b)
    run_btr(r drum "${scene}" -o "${WORK}/${run}" --steps 6 --check --quiet)
    expect_code(r 0)
  endforeach()
  expect_identical_series(s 4 steps "^([^,]*),([^,]*),[^,]*,[^,]*," "\\1,\\2,,," 8)  # steps 0 and 6; header + steps 0..6
  file(READ "${WORK}/a/${SCENE}.pvd" pvd)
  string(FIND "${pvd}" "timestep=\"21.6\" group=\"\" part=\"0\" file=\"${SCENE}_s000006.vtp\"" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${SCENE}.pvd does not list ${SCENE}_s000006.vtp at 21.6 degrees:\n${pvd}")
  endif()
  # DEM coupling of a drum snapshot is refused with the reason.
  run_btr(r relax "${WORK}/a/${SCENE}_s000006.csv" -o "${WORK}/relax")
  if("${r_code}" STREQUAL "0")
    message(FATAL_ERROR "btr relax accepted a drum packing:\n${r_text}")
  endif()
  expect_mentions(r "container 'drum'")
  expect_mentions(r "not supported")
  if(SCENE MATCHES "periodic")
    expect_mentions(r "(periodic ends)")
  endif()

elseif(CASE STREQUAL "redeposit_series")
  # Rigid clusters: same scene and seed twice give byte-identical snapshots (CSV with the cluster
  # column, VTP) and size tables; every cycle passes --check (no overlap, every cluster supported).
  foreach(run a b)
    run_btr(r redeposit "${scene}" -o "${WORK}/${run}" --cycles 2 --check --quiet)
    expect_code(r 0)
  endforeach()
  # cycles 0, 1, 2; the cycle table less its seconds column (header + 3 rows)
  expect_identical_series(c 6 cycles "^([^,]*),[^,]*," "\\1,," 4)
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${WORK}/a/${SCENE}_sizes.csv" "${WORK}/b/${SCENE}_sizes.csv"
                  RESULT_VARIABLE same)
  if(NOT same EQUAL 0)
    message(FATAL_ERROR "${SCENE}_sizes.csv differs between two runs with the same seed")
  endif()
  file(STRINGS "${WORK}/a/${SCENE}_c000000.csv" head LIMIT_COUNT 1)
  if(NOT head STREQUAL "id,x,y,z,radius,species,cluster")
    message(FATAL_ERROR "expected the cluster column in the header, got '${head}'")
  endif()

elseif(CASE STREQUAL "redeposit_without_table")
  run_btr(r redeposit "${scene}" -o "${WORK}/out")
  expect_code(r 2)
  expect_mentions(r "missing table [clusters]")

elseif(CASE STREQUAL "shake_without_table")
  run_btr(r shake "${scene}" -o "${WORK}/out")
  expect_code(r 2)
  expect_mentions(r "missing table [shaking]")

else()
  message(FATAL_ERROR "unknown case '${CASE}'")
endif()
