#include "modules/segment/SegmentLogic.h"

#include <array>
#include <cstdint>
#include <stdexcept>

#include <vtkCellArray.h>
#include <vtkMatrix3x3.h>
#include <vtkPoints.h>
#include <vtkTriangle.h>

#include "scene/LabelMapNode.h"
#include "scene/Scene.h"
#include "scene/SurfaceNode.h"
#include "scene/VolumeNode.h"
#include "segmentation/SurfaceExtraction.h"

namespace caps {
namespace {

// An unsigned char image with the geometry (origin, spacing, direction) of @a like.
vtkSmartPointer<vtkImageData> emptyLike(vtkImageData* like)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(like->GetDimensions());
  image->SetOrigin(like->GetOrigin());
  image->SetSpacing(like->GetSpacing());
  image->SetDirectionMatrix(like->GetDirectionMatrix());
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  return image;
}

std::int64_t voxelCount(vtkImageData* image)
{
  const int* d = image->GetDimensions();
  return static_cast<std::int64_t>(d[0]) * d[1] * d[2];
}

void requireLabels(vtkImageData* image, const char* what)
{
  if (!image || image->GetScalarType() != VTK_UNSIGNED_CHAR || image->GetNumberOfScalarComponents() != 1)
    throw std::invalid_argument(std::string(what) + ": an unsigned char image with one component is needed");
}

} // namespace

SegmentationOutput SegmentLogic::compute(vtkImageData* ct, const Parameters& parameters, const TaskProgress& progress)
{
  if (!ct)
    throw std::invalid_argument("The volume has no image data to segment.");
  if (parameters.boneThresholdHu <= parameters.skinThresholdHu)
    throw std::invalid_argument("The bone threshold (" + std::to_string(parameters.boneThresholdHu) +
                                " HU) must be above the skin threshold (" + std::to_string(parameters.skinThresholdHu) +
                                " HU).");
  seg::SegmentationParameters p;
  p.skinThresholdHu = parameters.skinThresholdHu;
  p.boneThresholdHu = parameters.boneThresholdHu;
  // The segmentation takes most of the time: 0 .. 0.85 of the bar.
  seg::ProgressCallback scaled;
  if (progress)
    scaled = [&progress](double f, const std::string& step) { return progress(0.85 * f, step); };
  seg::HeadMasks masks = seg::segmentHead(ct, p, scaled);

  SegmentationOutput out;
  out.labels = makeLabels(masks.body, masks.bone);
  out.notes = std::move(masks.notes);
  out.thresholds = {parameters.skinThresholdHu, parameters.boneThresholdHu};
  seg::reportProgress(progress, 0.85, "Skin surface");
  out.skinDisplay = displaySurface(masks.body);
  seg::reportProgress(progress, 0.93, "Bone surface");
  out.boneDisplay = displaySurface(masks.bone);
  seg::reportProgress(progress, 1.0, "Done");
  return out;
}

SegmentationResult SegmentLogic::addToScene(const VolumeNode& volume, SegmentationOutput output)
{
  Scene& s = scene();
  // An earlier segmentation of this volume, with its surfaces, is replaced.
  for (Node* node : s.nodesOfType(NodeType::LabelMap))
  {
    auto* old = static_cast<LabelMapNode*>(node);
    if (old->referenceVolumeId() != volume.id())
      continue;
    for (Node* surface : s.nodesOfType(NodeType::Surface))
      if (static_cast<SurfaceNode*>(surface)->sourceLabelMapId() == old->id())
        s.removeNode(surface->id());
    s.removeNode(old->id());
  }

  auto labels = std::make_unique<LabelMapNode>();
  labels->setName(volume.name() + " skin and bone");
  labels->setImage(output.labels);
  labels->setReferenceVolumeId(volume.id());
  labels->setThresholds(output.thresholds);
  labels->setLabels({{kBackgroundLabel, {"Background", {0.0, 0.0, 0.0}}},
                     {kSoftTissueLabel, {"Soft tissue", {0.90, 0.70, 0.55}}},
                     {kBoneLabel, {"Bone", {0.95, 0.93, 0.84}}}});
  auto* labelNode = static_cast<LabelMapNode*>(s.addNode(std::move(labels)));

  auto addSurface = [&](const char* name, vtkSmartPointer<vtkPolyData> polyData, const std::array<double, 3>& colour,
                        double opacity) {
    auto surface = std::make_unique<SurfaceNode>();
    surface->setName(name);
    surface->setPolyData(std::move(polyData));
    surface->setColor(colour);
    surface->setOpacity(opacity);
    surface->setSourceLabelMapId(labelNode->id());
    return s.addNode(std::move(surface))->id();
  };
  SegmentationResult ids;
  ids.labelMapId = labelNode->id();
  ids.skinSurfaceId = addSurface("Skin", output.skinDisplay, {0.90, 0.75, 0.65}, 0.6);
  ids.boneSurfaceId = addSurface("Bone", output.boneDisplay, {0.95, 0.93, 0.84}, 1.0);
  ids.notes = std::move(output.notes);
  return ids;
}

SegmentationResult SegmentLogic::segment(const VolumeNode& volume, const Parameters& parameters,
                                         const TaskProgress& progress)
{
  return addToScene(volume, compute(volume.image(), parameters, progress));
}

LabelMapNode* SegmentLogic::findLabelMap(const VolumeNode& volume) const
{
  LabelMapNode* found = nullptr;
  for (Node* node : scene().nodesOfType(NodeType::LabelMap))
    if (static_cast<LabelMapNode*>(node)->referenceVolumeId() == volume.id())
      found = static_cast<LabelMapNode*>(node);
  return found;
}

vtkSmartPointer<vtkImageData> SegmentLogic::makeLabels(vtkImageData* body, vtkImageData* bone)
{
  requireLabels(body, "body mask");
  requireLabels(bone, "bone mask");
  const int* d = body->GetDimensions();
  const int* e = bone->GetDimensions();
  if (d[0] != e[0] || d[1] != e[1] || d[2] != e[2])
    throw std::invalid_argument("The body and bone masks have different dimensions.");
  auto labels = emptyLike(body);
  const auto* b = static_cast<const unsigned char*>(body->GetScalarPointer());
  const auto* o = static_cast<const unsigned char*>(bone->GetScalarPointer());
  auto* l = static_cast<unsigned char*>(labels->GetScalarPointer());
  const std::int64_t n = voxelCount(body);
  for (std::int64_t v = 0; v < n; ++v)
    l[v] = o[v] ? kBoneLabel : (b[v] ? kSoftTissueLabel : kBackgroundLabel);
  return labels;
}

vtkSmartPointer<vtkImageData> SegmentLogic::maskOf(vtkImageData* labels, int minLabel)
{
  requireLabels(labels, "label map");
  auto mask = emptyLike(labels);
  const auto* l = static_cast<const unsigned char*>(labels->GetScalarPointer());
  auto* m = static_cast<unsigned char*>(mask->GetScalarPointer());
  const std::int64_t n = voxelCount(labels);
  for (std::int64_t v = 0; v < n; ++v)
    m[v] = l[v] >= minLabel ? 1 : 0;
  return mask;
}

vtkSmartPointer<vtkImageData> SegmentLogic::halfResolution(vtkImageData* mask)
{
  requireLabels(mask, "mask");
  const int* d = mask->GetDimensions();
  const int h[3] = {(d[0] + 1) / 2, (d[1] + 1) / 2, (d[2] + 1) / 2};
  const double* spacing = mask->GetSpacing();
  const double* origin = mask->GetOrigin();
  vtkMatrix3x3* direction = mask->GetDirectionMatrix();
  // The half-resolution voxel (i, j, k) covers full voxels 2i..2i+1: its centre
  // is half a full voxel past voxel 2i along each axis.
  double shift[3] = {0.5 * spacing[0], 0.5 * spacing[1], 0.5 * spacing[2]};
  double newOrigin[3];
  for (int r = 0; r < 3; ++r)
    newOrigin[r] = origin[r] + direction->GetElement(r, 0) * shift[0] + direction->GetElement(r, 1) * shift[1] +
                   direction->GetElement(r, 2) * shift[2];
  auto half = vtkSmartPointer<vtkImageData>::New();
  half->SetDimensions(h[0], h[1], h[2]);
  half->SetSpacing(2 * spacing[0], 2 * spacing[1], 2 * spacing[2]);
  half->SetOrigin(newOrigin);
  half->SetDirectionMatrix(direction);
  half->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  const auto* in = static_cast<const unsigned char*>(mask->GetScalarPointer());
  auto* out = static_cast<unsigned char*>(half->GetScalarPointer());
  std::int64_t o = 0;
  for (int k = 0; k < h[2]; ++k)
    for (int j = 0; j < h[1]; ++j)
      for (int i = 0; i < h[0]; ++i, ++o)
      {
        // Blocks cut by the image border count the voxels they have, out of 8.
        int inside = 0;
        for (int c = 0; c < 8; ++c)
        {
          const int x = 2 * i + (c & 1), y = 2 * j + ((c >> 1) & 1), z = 2 * k + (c >> 2);
          if (x < d[0] && y < d[1] && z < d[2])
            inside += in[(static_cast<std::int64_t>(z) * d[1] + y) * d[0] + x] != 0;
        }
        out[o] = inside >= 4 ? 1 : 0;
      }
  return half;
}

double SegmentLogic::volumeMm3(vtkImageData* labels, int minLabel)
{
  requireLabels(labels, "label map");
  const auto* l = static_cast<const unsigned char*>(labels->GetScalarPointer());
  const std::int64_t n = voxelCount(labels);
  std::int64_t count = 0;
  for (std::int64_t v = 0; v < n; ++v)
    count += l[v] >= minLabel;
  const double* s = labels->GetSpacing();
  return static_cast<double>(count) * s[0] * s[1] * s[2];
}

double SegmentLogic::surfaceAreaMm2(vtkPolyData* surface)
{
  if (!surface || !surface->GetPoints())
    return 0.0;
  vtkPoints* points = surface->GetPoints();
  double area = 0.0;
  vtkIdType n = 0;
  const vtkIdType* ids = nullptr;
  vtkCellArray* polys = surface->GetPolys();
  for (polys->InitTraversal(); polys->GetNextCell(n, ids);)
  {
    if (n != 3)
      continue;
    double a[3], b[3], c[3];
    points->GetPoint(ids[0], a);
    points->GetPoint(ids[1], b);
    points->GetPoint(ids[2], c);
    area += vtkTriangle::TriangleArea(a, b, c);
  }
  return area;
}

vtkSmartPointer<vtkPolyData> SegmentLogic::displaySurface(vtkImageData* mask)
{
  // Half resolution: about a quarter of the triangles of the full surface in
  // an eighth of the time, and no decimation pass (quadric decimation of the
  // full surface takes longer than the whole segmentation). Lighter smoothing
  // than the full surface: the voxels are already twice as big.
  seg::SurfaceOptions options;
  options.smoothingIterations = 15;
  options.smoothingPassBand = 0.1;
  return seg::extractSurface(halfResolution(mask), options);
}

vtkSmartPointer<vtkPolyData> SegmentLogic::fullSurface(vtkImageData* mask)
{
  seg::SurfaceOptions options; // 20 windowed-sinc iterations, pass band 0.1, no decimation
  return seg::extractSurface(mask, options);
}

} // namespace caps
