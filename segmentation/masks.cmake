# Sources of the skin/bone segmentation, added to caps_segmentation.
target_sources(caps_segmentation PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/HeadSegmentation.cpp
  ${CMAKE_CURRENT_LIST_DIR}/SurfaceExtraction.cpp)
