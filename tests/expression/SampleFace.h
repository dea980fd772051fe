#pragma once
// The embedded sample CT's skin and bone range maps and the landmarks placed
// on them automatically, read once per test program, for the Expression
// module's tests on a real face. The maps come from the demo scene (the
// ReportDemo fixture every expression test requires): `caps demo` builds
// them from the sample CT with the default parameters, exactly as
// RangeMapLogic::run would here (checked bit for bit), in a fraction of the
// time (about 12 s per test process otherwise).

#include <memory>
#include <stdexcept>

#include "modules/rangemap/RangeMapLogic.h"
#include "report/DemoScene.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/SceneBundle.h"
#include "segmentation/LandmarkPlacement.h"
#include "segmentation/RangeMap.h"

namespace caps::test {

struct SampleFace
{
  /// The range maps of the sample CT (RangeMapLogic::Parameters{}).
  struct Maps
  {
    seg::RangeMap skin; ///< r of the skin (mm)
    seg::RangeMap bone; ///< r of the bone (mm)
  } maps;
  seg::LandmarkPlacement landmarks;
};

/// The sample's range maps and landmarks, read on first use.
inline const SampleFace& sampleFace()
{
  static const std::unique_ptr<SampleFace> face = [] {
    auto out = std::make_unique<SampleFace>();
    Scene scene;
    loadSceneBundle(scene, reportDemoFolder() / "sample.caps");
    for (Node* n : scene.nodesOfType(NodeType::RangeMap))
    {
      const auto* map = static_cast<const RangeMapNode*>(n);
      if (map->role() == "skin")
        out->maps.skin = RangeMapLogic::toRangeMap(*map);
      else if (map->role() == "bone")
        out->maps.bone = RangeMapLogic::toRangeMap(*map);
    }
    if (out->maps.skin.empty() || out->maps.bone.empty())
      throw std::runtime_error("the demo scene " + (reportDemoFolder() / "sample.caps").string() +
                               " has no skin or bone range map: run `ctest -R report_demo_scene` again");
    out->landmarks = seg::placeLandmarks(out->maps.skin, out->maps.bone);
    return out;
  }();
  return *face;
}

} // namespace caps::test
