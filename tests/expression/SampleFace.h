#pragma once
// The embedded sample CT (data/sample-ct) read once per test program: its
// skin and bone range maps and the landmarks placed on them automatically,
// for the Expression module's tests on a real face.

#include <filesystem>
#include <memory>
#include <sstream>

#include "modules/rangemap/RangeMapLogic.h"
#include "modules/segment/SegmentCommands.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"
#include "segmentation/LandmarkPlacement.h"

namespace caps::test {

struct SampleFace
{
  RangeMapOutput maps;
  seg::LandmarkPlacement landmarks;
};

/// The sample's range maps and landmarks, computed on first use.
inline const SampleFace& sampleFace()
{
  static const std::unique_ptr<SampleFace> face = [] {
    auto out = std::make_unique<SampleFace>();
    Scene scene;
    RangeMapLogic logic(scene);
    std::ostringstream messages;
    VolumeNode* volume = cli::loadCt(logic, std::filesystem::path(CAPS_TEST_DATA_DIR) / "sample-ct" / "dicom",
                                     seg::CtReadOptions{}, messages);
    logic.run(*volume, RangeMapLogic::Parameters{}, {}, &out->maps);
    out->landmarks = seg::placeLandmarks(out->maps.skin, out->maps.bone);
    return out;
  }();
  return *face;
}

} // namespace caps::test
