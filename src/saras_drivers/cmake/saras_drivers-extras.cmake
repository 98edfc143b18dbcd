# saras_test_key_dir(<var>)
#
# Sets <var> to a directory holding throw-away keys for the rostests of the authenticated links
# (console.key, saras_arm.key: 64 hex digits, mode 0600, docs/touchball_protocol.md), created once
# per build tree. The .test files take it as the argument key_dir (add_rostest(... ARGS
# key_dir:=${dir})). CMake's string(RANDOM) is not a cryptographic generator: test keys only;
# deployment keys come from `python3 -m saras_drivers.keys <file>`.
function(saras_test_key_dir var)
  set(_dir ${CMAKE_BINARY_DIR}/saras_test_keys)
  foreach(_name console saras_arm)
    if(NOT EXISTS ${_dir}/${_name}.key)
      string(RANDOM LENGTH 64 ALPHABET 0123456789abcdef _key)
      file(WRITE ${_dir}/stage/${_name}.key "${_key}\n")
      file(COPY ${_dir}/stage/${_name}.key DESTINATION ${_dir} FILE_PERMISSIONS OWNER_READ OWNER_WRITE)
      file(REMOVE_RECURSE ${_dir}/stage)
    endif()
  endforeach()
  set(${var} ${_dir} PARENT_SCOPE)
endfunction()
