# mtpt_label_shuffled(TARGET LABEL): gives every test gtest_discover_tests found in the gtest
# program TARGET the labels LABEL and `shuffled`: scripts/ci/shuffled-tests.sh runs these
# programs whole, and scripts/test.sh --shuffled leaves them out of its ctest run.
# (gtest_discover_tests's PROPERTIES take one label only: it splits values at semicolons.)
# The labels are set when ctest reads the tests, after the discovered list.
function(mtpt_label_shuffled target label)
  set(file "${CMAKE_CURRENT_BINARY_DIR}/${target}_labels.cmake")
  file(WRITE "${file}" "if(${target}_TESTS)\n"
    "  set_tests_properties(\${${target}_TESTS} PROPERTIES LABELS \"${label};shuffled\")\n"
    "endif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${file}")
endfunction()
