foresight_add_test(otnet_encoding_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet/map_encoding_test.cc ${CMAKE_CURRENT_SOURCE_DIR}/otnet/trajectory_test.cc
  DEPS foresight_otnet_encoding foresight_test_util
  PREFIX otnet.)
foresight_add_test(otnet_encoding_alloc_tests
  SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/otnet/encoding_alloc_test.cc
  DEPS foresight_otnet_encoding foresight_test_util
  PREFIX otnet.)
