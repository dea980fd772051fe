# Sources of landmarks, their depths, metal artefacts and thickness painting.
target_sources(caps_segmentation PRIVATE
  ${CMAKE_CURRENT_LIST_DIR}/LandmarkDepth.cpp
  ${CMAKE_CURRENT_LIST_DIR}/MetalArtefacts.cpp
  ${CMAKE_CURRENT_LIST_DIR}/LandmarkPlacement.cpp
  ${CMAKE_CURRENT_LIST_DIR}/Landmarks.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ThicknessPainting.cpp)
