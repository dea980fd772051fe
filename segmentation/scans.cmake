# Sources of surface scan import, range/colour map images and calibration.
target_sources(caps_segmentation PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/Calibration.cpp
  ${CMAKE_CURRENT_LIST_DIR}/RangeMapImage.cpp
  ${CMAKE_CURRENT_LIST_DIR}/SurfaceScan.cpp)
# PLY/OBJ readers and PNG images.
target_link_libraries(caps_segmentation PRIVATE VTK::IOPLY VTK::IOGeometry VTK::IOImage)
