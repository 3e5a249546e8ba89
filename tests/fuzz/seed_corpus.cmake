# Builds the fuzzers' starting corpora in the build tree, fuzz/corpus/<format>/, from inputs the
# repository already has: experiment configs, simulation profiles, the paper's measurement, the flux
# map in experiments/pmsm/data, model specs the docs use, the binary seeds, and every regression
# file. Nothing is copied into the source tree. Large files are cut to their first lines: libFuzzer
# sizes its inputs after the largest seed, and a 130 kB seed would slow every execution for little.

set(MHBENCH_FUZZ_SEED_BYTES 8192)

function(mhbench_add_seed format file)
  set(corpus ${CMAKE_BINARY_DIR}/fuzz/corpus/${format})
  file(READ ${file} content LIMIT ${MHBENCH_FUZZ_SEED_BYTES})
  file(SIZE ${file} size)
  if(size GREATER MHBENCH_FUZZ_SEED_BYTES)
    # Keep whole lines, so the cut seed is still a well-formed file of its format.
    string(FIND "${content}" "\n" last_newline REVERSE)
    string(SUBSTRING "${content}" 0 ${last_newline} content)
    string(APPEND content "\n")
  endif()
  get_filename_component(name ${file} NAME)
  file(WRITE ${corpus}/${name} "${content}")
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${file})
endfunction()

file(GLOB experiment_seeds ${PROJECT_SOURCE_DIR}/experiments/*.toml)
# Every profile has [[segment]] tables; the study files beside them are another format.
file(GLOB pmsm_tomls ${PROJECT_SOURCE_DIR}/experiments/pmsm/*.toml)
set(simulation_profile_seeds)
foreach(file IN LISTS pmsm_tomls)
  file(STRINGS ${file} segment_lines REGEX "^\\[\\[segment\\]\\]")
  if(segment_lines)
    list(APPEND simulation_profile_seeds ${file})
  endif()
endforeach()
file(GLOB measurement_seeds ${PROJECT_SOURCE_DIR}/experiments/pmsm/*.csv)
file(GLOB flux_map_seeds ${PROJECT_SOURCE_DIR}/experiments/pmsm/data/*fluxmap*.csv)

foreach(format experiment simulation_profile measurement flux_map model_spec)
  file(MAKE_DIRECTORY ${CMAKE_BINARY_DIR}/fuzz/corpus/${format})
  file(GLOB regressions CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/fuzz/regressions/${format}/*)
  foreach(file IN LISTS ${format}_seeds regressions)
    mhbench_add_seed(${format} ${file})
  endforeach()
endforeach()

# The binary formats start from the valid files of every documented layout in tests/fuzz/seeds/
# (written by the hidden test "[.write_fuzz_seeds]" in tests/fuzz_regression_test.cpp), copied
# whole: cutting a binary file at a line would damage it.
foreach(format mat5 mat73 hdf5)
  file(MAKE_DIRECTORY ${CMAKE_BINARY_DIR}/fuzz/corpus/${format})
  file(GLOB binary_seeds CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/tests/fuzz/seeds/${format}/*
       ${PROJECT_SOURCE_DIR}/tests/fuzz/regressions/${format}/*)
  foreach(file IN LISTS binary_seeds)
    file(COPY ${file} DESTINATION ${CMAKE_BINARY_DIR}/fuzz/corpus/${format})
  endforeach()
endforeach()

# Model specs are command-line text, not files: the forms the docs use.
set(model_spec_seed_index 0)
foreach(spec "base" "base+deadtime" "base+deadtime+delay(tau=150e-6)" "base+deadtime(current_band=0)"
             "base+rs_thermal+deadtime+encoder_offset+flux_harmonic" "base+saturation" "base+rs_thermal+psi_thermal"
             "base+current_offset+voltage_offset")
  file(WRITE ${CMAKE_BINARY_DIR}/fuzz/corpus/model_spec/docs_${model_spec_seed_index} "${spec}")
  math(EXPR model_spec_seed_index "${model_spec_seed_index} + 1")
endforeach()
