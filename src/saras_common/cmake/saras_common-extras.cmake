# saras_add_pytest(<dir> [NAME <name>] [ARGS <pytest args>...])
#
# Registers the pytest suite found under <dir> (relative to the calling package) with catkin's
# run_tests, like catkin_add_nosetests does for nose: `catkin_make run_tests` (or
# `make -C build run_tests`) runs it, and its JUnit result lands in the package's test_results
# folder where catkin_test_results finds it. Run with Debian's /usr/bin/python3.
function(saras_add_pytest dir)
  cmake_parse_arguments(_sp "" "NAME" "ARGS" ${ARGN})
  if(NOT _sp_NAME)
    string(REPLACE "/" "_" _sp_NAME "${dir}")
  endif()
  set(_xml "pytest-${_sp_NAME}.xml")
  # catkin's run_tests.py runs each COMMAND argument as one shell command line
  string(REPLACE ";" " " _args "${_sp_ARGS}")
  catkin_run_tests_target("pytest" ${_sp_NAME} ${_xml}
    COMMAND "/usr/bin/python3 -m pytest -q -p no:cacheprovider ${_args} --junitxml=${CATKIN_TEST_RESULTS_DIR}/${PROJECT_NAME}/${_xml} ${PROJECT_SOURCE_DIR}/${dir}"
    WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
endfunction()
