# Sources of the cylindrical frame, range maps and thickness, added to caps_segmentation.
target_sources(caps_segmentation PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/CylindricalFrame.cpp
  ${CMAKE_CURRENT_LIST_DIR}/HeadAxis.cpp
  ${CMAKE_CURRENT_LIST_DIR}/RangeMap.cpp
  ${CMAKE_CURRENT_LIST_DIR}/RangeMapBuilder.cpp
  ${CMAKE_CURRENT_LIST_DIR}/RangeMapFromPoints.cpp
  ${CMAKE_CURRENT_LIST_DIR}/RangeMapImageGeometry.cpp
  ${CMAKE_CURRENT_LIST_DIR}/RangeMapParallel.cpp
  ${CMAKE_CURRENT_LIST_DIR}/Thickness.cpp)
# The range map and thickness loops run on std::thread.
target_link_libraries(caps_segmentation PRIVATE Threads::Threads)
