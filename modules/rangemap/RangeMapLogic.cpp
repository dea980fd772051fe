#include "modules/rangemap/RangeMapLogic.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <memory>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "modules/segment/SegmentLogic.h"
#include "scene/LabelMapNode.h"
#include "scene/PlanNode.h"
#include "scene/RangeMapNode.h"
#include "scene/Scene.h"
#include "scene/VolumeNode.h"
#include "segmentation/LandmarkDepth.h"
#include "segmentation/RangeMapBuilder.h"

namespace caps {
namespace {

// The part [from, to] of the progress bar.
seg::ProgressCallback part(const TaskProgress& progress, double from, double to)
{
  if (!progress)
    return {};
  return [&progress, from, to](double f, const std::string& step) { return progress(from + (to - from) * f, step); };
}

} // namespace

RangeMapOutput RangeMapLogic::compute(vtkImageData* ct, vtkImageData* labels, const Parameters& parameters,
                                      const TaskProgress& progress)
{
  if (!ct || !labels)
    throw std::invalid_argument("A CT and its skin/bone label map are needed for range maps.");
  if (parameters.nTheta < 4 || parameters.nZ < 2)
    throw std::invalid_argument("The range map needs at least 4 x 2 samples (got " + std::to_string(parameters.nTheta) +
                                " x " + std::to_string(parameters.nZ) + ").");
  seg::reportProgress(progress, 0.0, "Head axis");
  const auto body = SegmentLogic::maskOf(labels, kSoftTissueLabel);
  const auto bone = SegmentLogic::maskOf(labels, kBoneLabel);
  seg::HeadAxisOptions axisOptions;
  axisOptions.nTheta = parameters.nTheta;
  axisOptions.nZ = parameters.nZ;
  RangeMapOutput out;
  out.axis = parameters.axis
               ? seg::axisThroughBody(body, parameters.axis->point, parameters.axis->direction, axisOptions)
               : seg::fitHeadAxis(body, axisOptions);

  seg::reportProgress(progress, 0.05, "Skin and bone range maps");
  seg::RangeMapBuildOptions build;
  build.skinThreshold = parameters.skinThresholdHu;
  build.boneThreshold = parameters.boneThresholdHu;
  build.progress = part(progress, 0.05, 0.65);
  seg::SkinBoneRangeMaps maps = seg::buildRangeMaps(ct, body, bone, out.axis.frame, build);
  out.skinFromMaskEdge = maps.skinFromMaskEdge;
  out.boneFromMaskEdge = maps.boneFromMaskEdge;
  if (parameters.smooth)
  {
    seg::reportProgress(progress, 0.65, "Smoothing");
    out.skin = seg::boxSmooth(maps.skin);
    out.bone = seg::boxSmooth(maps.bone);
  }
  else
  {
    out.skin = std::move(maps.skin);
    out.bone = std::move(maps.bone);
  }

  seg::reportProgress(progress, 0.67, "Radial thickness");
  out.thickness = seg::radialThickness(out.skin, out.bone);
  seg::reportProgress(progress, 0.70, "Thickness along the skin normal");
  seg::NormalThicknessOptions normal;
  normal.progress = part(progress, 0.70, 0.98);
  out.thicknessNormal = seg::normalThickness(out.skin, out.bone, normal);
  out.radialStatistics = seg::thicknessStatistics(out.thickness);
  out.normalStatistics = seg::thicknessStatistics(out.thicknessNormal);
  seg::reportProgress(progress, 1.0, "Done");
  return out;
}

RangeMapLogic::Parameters RangeMapLogic::forLabelMap(Parameters parameters, const LabelMapNode& labels)
{
  if (const auto& made = labels.thresholds())
  {
    parameters.skinThresholdHu = made->skinHu;
    parameters.boneThresholdHu = made->boneHu;
  }
  return parameters;
}

RangeMapResult RangeMapLogic::addToScene(const VolumeNode& volume, const RangeMapOutput& output,
                                         const NodeId& labelMapId)
{
  Scene& s = scene();
  const std::vector<NodeId> replaced = mapsOfVolume(s, volume);
  for (const auto& id : replaced)
    s.removeNode(id);

  const seg::CylindricalFrame& frame = output.skin.frame();
  NodeId skinId;
  auto add = [&](const seg::RangeMap& map, const char* role, const std::string& name) {
    auto node = std::make_unique<RangeMapNode>();
    node->setName(volume.name() + " " + name);
    node->setValues(toMatrix(map));
    node->setRole(role);
    node->setAxis(frame.origin(), frame.direction());
    node->setZRange(frame.zMin(), frame.zMax());
    node->setSourceVolumeId(volume.id());
    node->setSourceLabelMapId(labelMapId);
    auto* added = s.addNode(std::move(node));
    // The skin map is added first; every map of the run names it.
    if (skinId.empty())
      skinId = added->id();
    static_cast<RangeMapNode*>(added)->setSkinMapId(skinId);
    return added->id();
  };
  RangeMapResult result;
  result.skinId = add(output.skin, "skin", "skin range");
  result.boneId = add(output.bone, "bone", "bone range");
  result.thicknessId = add(output.thickness, "thickness", "thickness (radial)");
  result.thicknessNormalId = add(output.thicknessNormal, "thickness-normal", "thickness (along the skin normal)");
  result.labelMapId = labelMapId;

  for (Node* node : s.nodesOfType(NodeType::Plan))
  {
    auto* plan = static_cast<PlanNode*>(node);
    if (std::find(replaced.begin(), replaced.end(), plan->rangeMapId()) != replaced.end())
      plan->setRangeMapId(result.skinId);
  }
  return result;
}

std::vector<NodeId> RangeMapLogic::mapsOfVolume(const Scene& scene, const VolumeNode& volume)
{
  std::vector<NodeId> ids;
  for (Node* node : scene.nodesOfType(NodeType::RangeMap))
    if (static_cast<RangeMapNode*>(node)->sourceVolumeId() == volume.id())
      ids.push_back(node->id());
  return ids;
}

namespace {

const RangeMapNode* newestOfRole(const Scene& scene, const std::string& role)
{
  const RangeMapNode* found = nullptr;
  for (Node* node : scene.nodesOfType(NodeType::RangeMap))
    if (static_cast<const RangeMapNode*>(node)->role() == role)
      found = static_cast<const RangeMapNode*>(node);
  return found;
}

} // namespace

const RangeMapNode* RangeMapLogic::builtWith(const Scene& scene, const RangeMapNode& skin, const std::string& role)
{
  // A skin map without provenance (an older scene): the newest of the role.
  if (skin.skinMapId().empty())
    return newestOfRole(scene, role);
  for (Node* node : scene.nodesOfType(NodeType::RangeMap))
  {
    const auto* map = static_cast<const RangeMapNode*>(node);
    if (map->role() == role && map->skinMapId() == skin.id())
      return map;
  }
  return nullptr;
}

SkinAndBoneMaps RangeMapLogic::newestMaps(const Scene& scene)
{
  SkinAndBoneMaps maps;
  maps.skin = newestOfRole(scene, "skin");
  if (maps.skin)
    maps.bone = builtWith(scene, *maps.skin, "bone");
  return maps;
}

SkinAndBoneMaps RangeMapLogic::mapsOf(const Scene& scene, const PlanNode& plan)
{
  const auto* own = scene.nodeAs<RangeMapNode>(plan.rangeMapId());
  if (!own || own->role() != "skin")
    return newestMaps(scene);
  return {own, builtWith(scene, *own, "bone")};
}

RangeMapResult RangeMapLogic::run(const VolumeNode& volume, const Parameters& parameters, const TaskProgress& progress,
                                  RangeMapOutput* output)
{
  SegmentLogic segment(scene());
  LabelMapNode* labels = segment.findLabelMap(volume);
  bool segmented = false;
  if (!labels)
  {
    SegmentLogic::Parameters p;
    p.skinThresholdHu = parameters.skinThresholdHu;
    p.boneThresholdHu = parameters.boneThresholdHu;
    const SegmentationResult made = segment.segment(volume, p, part(progress, 0.0, 0.5));
    labels = scene().nodeAs<LabelMapNode>(made.labelMapId);
    segmented = true;
  }
  RangeMapOutput computed = compute(volume.image(), labels->image(), forLabelMap(parameters, *labels),
                                    segmented ? part(progress, 0.5, 1.0) : progress);
  RangeMapResult result = addToScene(volume, computed, labels->id());
  result.segmented = segmented;
  if (output)
    *output = std::move(computed);
  return result;
}

bool RangeMapLogic::measureLandmarkDepths(const VolumeNode& volume, std::vector<seg::LandmarkThickness>& rows) const
{
  SegmentLogic segment(scene());
  const LabelMapNode* labels = segment.findLabelMap(volume);
  if (!labels)
    return false;
  const Parameters thresholds = forLabelMap(Parameters{}, *labels);
  const auto bone = SegmentLogic::maskOf(labels->image(), kBoneLabel);
  const seg::BoneDepthProbe probe(volume.image(), bone, thresholds.boneThresholdHu, thresholds.skinThresholdHu);
  const std::vector<seg::MetalPiece>& metal = metalOf(volume);
  for (seg::LandmarkThickness& row : rows)
  {
    const seg::LandmarkDepth d{row.landmark, seg::depthConventionOf(row.landmark.name), probe.measure(row.position)};
    row.ctSkinNormal = d.bone.alongSkinNormal;
    row.ctNearestBone = d.bone.toNearestBone;
    row.depth = d.depth();
    row.convention = d.describeConvention();
    row.depthSkinEnd = d.bone.skinPoint;
    row.depthBoneEnd = d.boneEnd();
    row.note.clear();
    if (const seg::MetalPiece* piece = seg::streaksAt(metal, volume.image(), row.position))
    {
      std::ostringstream note;
      note.precision(0);
      note << std::fixed << "in the streaks of the metal or contrast at (" << piece->centroid.x() << " "
           << piece->centroid.y() << " " << piece->centroid.z() << ") mm: check it on the slices";
      row.note = note.str();
    }
  }
  return true;
}

std::function<bool(const Eigen::Vector3d&)> RangeMapLogic::againstAnObject(const VolumeNode& volume,
                                                                           const seg::CylindricalFrame& frame) const
{
  SegmentLogic segment(scene());
  const LabelMapNode* labels = segment.findLabelMap(volume);
  if (!labels || !volume.image())
    return {};
  const double skinThreshold = forLabelMap(Parameters{}, *labels).skinThresholdHu;
  vtkSmartPointer<vtkImageData> ct(volume.image());
  auto sampler = std::make_shared<const seg::CtSampler>(ct);
  return [ct, sampler, frame, skinThreshold](const Eigen::Vector3d& p) {
    return seg::skinAgainstAnObject(*sampler, p, frame.radialDirection(frame.toCylindrical(p).theta), skinThreshold);
  };
}

const std::vector<seg::MetalPiece>& RangeMapLogic::metalOf(const VolumeNode& volume) const
{
  vtkImageData* image = volume.image();
  if (!image)
  {
    metal_ = {};
    return metal_.pieces;
  }
  if (metal_.image != image || metal_.modified != image->GetMTime())
    metal_ = {image, image->GetMTime(), seg::findMetal(image)};
  return metal_.pieces;
}

Eigen::MatrixXf RangeMapLogic::toMatrix(const seg::RangeMap& map)
{
  Eigen::MatrixXf m(map.nTheta(), map.nZ());
  for (int j = 0; j < map.nZ(); ++j)
    for (int i = 0; i < map.nTheta(); ++i)
      m(i, j) = map.at(i, j);
  return m;
}

seg::RangeMap RangeMapLogic::toRangeMap(const RangeMapNode& node)
{
  const Eigen::MatrixXf& m = node.values();
  const seg::CylindricalFrame frame(node.axisOrigin(), node.axisDirection(), node.zMin(), node.zMax(),
                                    static_cast<int>(m.rows()), static_cast<int>(m.cols()));
  seg::RangeMap map(frame);
  for (int j = 0; j < map.nZ(); ++j)
    for (int i = 0; i < map.nTheta(); ++i)
      map.at(i, j) = m(i, j);
  return map;
}

std::string RangeMapLogic::describeAxis(const seg::HeadAxisFit& axis)
{
  const seg::CylindricalFrame& f = axis.frame;
  const Eigen::Vector3d& o = f.origin();
  const Eigen::Vector3d d = f.direction().array() + 0.0; // + 0.0: no "-0.000"
  const double tilt = std::acos(std::clamp(d.z(), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  std::ostringstream out;
  out << std::fixed << std::setprecision(1);
  out << "Axis: through (" << o.x() << ", " << o.y() << ", " << o.z() << ") mm LPS, direction (" << std::setprecision(3)
      << d.x() << ", " << d.y() << ", " << d.z() << "), " << std::setprecision(1) << tilt
      << " deg from patient superior\n";
  if (axis.userDefined)
    out << "      set by the user";
  else
    out << "      fitted to " << axis.slicesUsed << " of " << axis.centroids.size() << " slice centroids, RMS residual "
        << std::setprecision(2) << axis.rmsResidual << " mm";
  out << "; z from " << std::setprecision(1) << f.zMin() << " to " << f.zMax() << " mm, " << f.nTheta() << " x "
      << f.nZ() << " samples (" << std::setprecision(2) << 360.0 / f.nTheta() << " deg x " << f.zStep() << " mm)\n";
  return out.str();
}

} // namespace caps
