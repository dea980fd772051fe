# One copy of each CAPS library in a process. A static library linked into
# several plugins puts several copies of its code and of its static state in
# the app (a stale copy once corrupted the heap), so every caps_ library is
# shared: checked here when configuring, and on the built binaries by the
# test OneCopyOfEachLibrary (tests/app/one_copy_of_each_library.sh).

# All build-system targets under @a dir, recursively.
function(caps_targets_under dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    caps_targets_under(${sub} more)
    list(APPEND targets ${more})
  endforeach()
  set(${out} ${targets} PARENT_SCOPE)
endfunction()

caps_targets_under(${CMAKE_SOURCE_DIR} caps_all_targets)
set(caps_binaries "")
foreach(target IN LISTS caps_all_targets)
  get_target_property(type ${target} TYPE)
  if(type STREQUAL "STATIC_LIBRARY" AND target MATCHES "^caps_")
    message(FATAL_ERROR "${target} is a static library: every CAPS library is shared, so the "
                        "app and its plugins hold one copy of it. Drop STATIC from its add_library.")
  endif()
  if(type MATCHES "^(SHARED_LIBRARY|MODULE_LIBRARY|EXECUTABLE)$")
    string(APPEND caps_binaries "$<TARGET_FILE:${target}>\n")
  endif()
endforeach()

if(CAPS_BUILD_TESTS)
  file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/one-copy-of-each-library.txt CONTENT "${caps_binaries}")
  add_test(NAME OneCopyOfEachLibrary
    COMMAND bash ${CMAKE_SOURCE_DIR}/tests/app/one_copy_of_each_library.sh
            ${CMAKE_BINARY_DIR}/one-copy-of-each-library.txt)
  set_tests_properties(OneCopyOfEachLibrary PROPERTIES LABELS app)
endif()
