/// @file HeadSegmentation.cpp
/// @brief Body and bone masks of a head CT (ITK in index space, VTK images out).

#include "segmentation/HeadSegmentation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <itkBinaryDilateImageFilter.h>
#include <itkBinaryErodeImageFilter.h>
#include <itkBinaryImageToLabelMapFilter.h>
#include <itkBinaryShapeKeepNObjectsImageFilter.h>
#include <itkBinaryShapeOpeningImageFilter.h>
#include <itkCommand.h>
#include <itkFlatStructuringElement.h>
#include <itkImage.h>
#include <itkLabelMap.h>
#include <itkLabelObject.h>
#include <itkProcessObject.h>

#include <vtkMatrix3x3.h>
#include <vtkPointData.h>
#include <vtkType.h>

namespace caps::seg {
namespace {

using Mask = itk::Image<unsigned char, 3>;
using Kernel = itk::FlatStructuringElement<3>;

/// Reports progress in a sub-range [begin, end] of the whole and throws
/// Cancelled when the callback asks to stop.
class Reporter
{
public:
  explicit Reporter(const ProgressCallback& callback) : callback_(callback) {}

  void report(double fraction, const std::string& step) const
  {
    if (callback_ && !callback_(std::clamp(fraction, 0.0, 1.0), step))
      throw Cancelled();
  }

  /// Same as report() but returns false instead of throwing (for ITK observers).
  bool tryReport(double fraction, const std::string& step) const
  {
    return !callback_ || callback_(std::clamp(fraction, 0.0, 1.0), step);
  }

  bool active() const { return static_cast<bool>(callback_); }

private:
  const ProgressCallback& callback_;
};

/// Runs an ITK filter, forwarding its progress into [begin, end] and aborting
/// it when the user cancels. Only events of the calling thread are forwarded.
void runFilter(itk::ProcessObject* filter, const Reporter& reporter, double begin, double end, const std::string& step)
{
  reporter.report(begin, step);
  bool cancelled = false;
  unsigned long tag = 0;
  if (reporter.active())
  {
    auto command = itk::CStyleCommand::New();
    struct Context
    {
      itk::ProcessObject* filter;
      const Reporter* reporter;
      double begin, end;
      const std::string* step;
      bool* cancelled;
      std::thread::id thread;
    };
    static thread_local Context context;
    context = {filter, &reporter, begin, end, &step, &cancelled, std::this_thread::get_id()};
    command->SetClientData(&context);
    command->SetConstCallback([](const itk::Object* object, const itk::EventObject&, void* data) {
      auto* c = static_cast<Context*>(data);
      if (std::this_thread::get_id() != c->thread || *c->cancelled)
        return;
      const double f = static_cast<const itk::ProcessObject*>(object)->GetProgress();
      if (!c->reporter->tryReport(c->begin + f * (c->end - c->begin), *c->step))
      {
        *c->cancelled = true;
        c->filter->AbortGenerateDataOn();
      }
    });
    tag = filter->AddObserver(itk::ProgressEvent(), command);
  }
  try
  {
    filter->Update();
  }
  catch (const itk::ProcessAborted&)
  {
    throw Cancelled();
  }
  if (reporter.active())
    filter->RemoveObserver(tag);
  if (cancelled)
    throw Cancelled();
}

/// An empty mask in index space: spacing |spacing| (so physical sizes are in
/// mm and mm³), origin 0, identity direction. Morphology needs nothing more.
Mask::Pointer newMask(const int dims[3], const double spacing[3])
{
  auto mask = Mask::New();
  Mask::RegionType region;
  Mask::SizeType size;
  Mask::SpacingType itkSpacing;
  for (int a = 0; a < 3; ++a)
  {
    size[a] = static_cast<itk::SizeValueType>(dims[a]);
    itkSpacing[a] = std::abs(spacing[a]);
  }
  region.SetSize(size);
  mask->SetRegions(region);
  mask->SetSpacing(itkSpacing);
  mask->Allocate(true);
  return mask;
}

/// A ball of radius mm, as voxel radii per axis (at least 1).
Kernel ballKernel(double radiusMm, const double spacing[3])
{
  Kernel::RadiusType radius;
  for (int a = 0; a < 3; ++a)
    radius[a] = static_cast<itk::SizeValueType>(std::max(1.0, std::round(radiusMm / std::abs(spacing[a]))));
  return Kernel::Ball(radius);
}

template <typename T> void thresholdBuffer(const T* ct, std::size_t count, double threshold, unsigned char* out)
{
  for (std::size_t i = 0; i < count; ++i)
    out[i] = static_cast<double>(ct[i]) > threshold ? 1 : 0;
}

template <typename T>
void thresholdInside(const T* ct, const unsigned char* inside, std::size_t count, double threshold, unsigned char* out)
{
  for (std::size_t i = 0; i < count; ++i)
    out[i] = inside[i] && static_cast<double>(ct[i]) > threshold ? 1 : 0;
}

std::size_t countOnes(const unsigned char* data, std::size_t count)
{
  std::size_t n = 0;
  for (std::size_t i = 0; i < count; ++i)
    n += data[i] != 0;
  return n;
}

/// Keeps the largest 6-connected component (by voxel count) of a 0/1 mask.
Mask::Pointer largestComponent(Mask* mask, const Reporter& reporter, double begin, double end, const std::string& step)
{
  using Filter = itk::BinaryShapeKeepNObjectsImageFilter<Mask>;
  auto filter = Filter::New();
  filter->SetInput(mask);
  filter->SetForegroundValue(1);
  filter->SetBackgroundValue(0);
  filter->SetNumberOfObjects(1);
  filter->SetReverseOrdering(false);
  filter->SetFullyConnected(false);
  filter->SetAttribute(Filter::LabelObjectType::NUMBER_OF_PIXELS);
  runFilter(filter, reporter, begin, end, step);
  Mask::Pointer out = filter->GetOutput();
  out->DisconnectPipeline();
  return out;
}

/// Strides of an image with dims, and the two in-plane axes of the slices
/// normal to `axis`.
struct SliceLayout
{
  std::array<std::int64_t, 3> stride;
  int u, v;
};

SliceLayout sliceLayout(const int dims[3], int axis)
{
  SliceLayout layout{{1, dims[0], std::int64_t{dims[0]} * dims[1]}, 0, 0};
  layout.u = axis == 0 ? 1 : 0;
  layout.v = axis == 2 ? 1 : 2;
  return layout;
}

/// Fills, in every slice normal to `axis`, the background not 4-connected to
/// the slice border. Returns the number of voxels filled.
std::size_t fillHolesInSlices(unsigned char* mask, const int dims[3], int axis, const Reporter& reporter, double begin,
                              double end)
{
  const SliceLayout layout = sliceLayout(dims, axis);
  const int nu = dims[layout.u], nv = dims[layout.v], ns = dims[axis];
  const std::int64_t su = layout.stride[layout.u], sv = layout.stride[layout.v], ss = layout.stride[axis];
  std::vector<unsigned char> outside(static_cast<std::size_t>(nu) * nv);
  std::vector<int> stack;
  std::size_t filled = 0;
  for (int s = 0; s < ns; ++s)
  {
    if (s % 16 == 0)
      reporter.report(begin + (end - begin) * s / ns, "Filling internal air (slices)");
    unsigned char* slice = mask + s * ss;
    auto at = [&](int p) -> unsigned char& { return slice[(p % nu) * su + (p / nu) * sv]; };
    std::fill(outside.begin(), outside.end(), 0);
    stack.clear();
    auto seed = [&](int p) {
      if (!outside[p] && at(p) == 0)
      {
        outside[p] = 1;
        stack.push_back(p);
      }
    };
    for (int i = 0; i < nu; ++i)
    {
      seed(i);
      seed((nv - 1) * nu + i);
    }
    for (int j = 0; j < nv; ++j)
    {
      seed(j * nu);
      seed(j * nu + nu - 1);
    }
    while (!stack.empty())
    {
      const int p = stack.back();
      stack.pop_back();
      const int i = p % nu, j = p / nu;
      if (i > 0)
        seed(p - 1);
      if (i < nu - 1)
        seed(p + 1);
      if (j > 0)
        seed(p - nu);
      if (j < nv - 1)
        seed(p + nu);
    }
    for (int p = 0; p < nu * nv; ++p)
      if (!outside[p] && at(p) == 0)
      {
        at(p) = 1;
        ++filled;
      }
  }
  return filled;
}

/// Fills every 6-connected background component that does not touch the
/// image border. Returns the number of voxels filled and of cavities.
std::pair<std::size_t, std::size_t> fillCavities3d(Mask* mask, const Reporter& reporter, double begin, double end)
{
  using LabelMap = itk::LabelMap<itk::LabelObject<std::uint32_t, 3>>;
  using Filter = itk::BinaryImageToLabelMapFilter<Mask, LabelMap>;
  auto filter = Filter::New();
  filter->SetInput(mask);
  filter->SetInputForegroundValue(0); // the components of the background
  filter->SetFullyConnected(false);
  runFilter(filter, reporter, begin, end, "Filling internal air (3D)");
  LabelMap* labels = filter->GetOutput();
  const auto size = mask->GetLargestPossibleRegion().GetSize();
  const auto nx = static_cast<itk::IndexValueType>(size[0]), ny = static_cast<itk::IndexValueType>(size[1]),
             nz = static_cast<itk::IndexValueType>(size[2]);
  std::size_t filled = 0, cavities = 0;
  for (std::size_t n = 0; n < labels->GetNumberOfLabelObjects(); ++n)
  {
    const auto* object = labels->GetNthLabelObject(n);
    bool touchesBorder = false;
    for (std::size_t l = 0; l < object->GetNumberOfLines() && !touchesBorder; ++l)
    {
      const auto& line = object->GetLine(l);
      const auto& idx = line.GetIndex();
      const auto length = static_cast<itk::IndexValueType>(line.GetLength());
      touchesBorder =
        idx[0] == 0 || idx[0] + length >= nx || idx[1] == 0 || idx[1] == ny - 1 || idx[2] == 0 || idx[2] == nz - 1;
    }
    if (touchesBorder)
      continue;
    ++cavities;
    for (std::size_t l = 0; l < object->GetNumberOfLines(); ++l)
    {
      const auto& line = object->GetLine(l);
      auto idx = line.GetIndex();
      for (itk::SizeValueType k = 0; k < line.GetLength(); ++k, ++idx[0])
        mask->SetPixel(idx, 1);
      filled += line.GetLength();
    }
  }
  return {filled, cavities};
}

vtkSmartPointer<vtkImageData> toVtkMask(const Mask* mask, vtkImageData* geometry)
{
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetExtent(geometry->GetExtent());
  image->SetOrigin(geometry->GetOrigin());
  image->SetSpacing(geometry->GetSpacing());
  image->SetDirectionMatrix(geometry->GetDirectionMatrix());
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  std::memcpy(image->GetScalarPointer(), mask->GetBufferPointer(),
              static_cast<std::size_t>(image->GetNumberOfPoints()));
  return image;
}

std::string formatVolume(double mm3)
{
  std::ostringstream s;
  s.precision(mm3 >= 1e5 ? 3 : 1);
  if (mm3 >= 1e5)
    s << std::fixed << mm3 * 1e-6 << " L";
  else
    s << std::fixed << mm3 * 1e-3 << " cm³";
  return s.str();
}

void checkSegmentationInputs(vtkImageData* ct, const SegmentationParameters& parameters)
{
  if (!ct || ct->GetNumberOfPoints() == 0 || !ct->GetPointData()->GetScalars())
    throw std::invalid_argument("The CT volume is empty: there is nothing to segment.");
  if (ct->GetNumberOfScalarComponents() != 1)
    throw std::invalid_argument("The CT volume has " + std::to_string(ct->GetNumberOfScalarComponents()) +
                                " components per voxel; segmentation needs one (HU).");
  if (parameters.openingRadiusMm < 0 || parameters.reconstructionMarginMm < 0 || parameters.minBoneIslandMm3 < 0 ||
      parameters.maxBoneHoleMm3 < 0 || parameters.maxReattachedPieceMm3 < 0)
    throw std::invalid_argument("Segmentation radii and volumes must not be negative.");
}

/// The CT's voxel grid, as the steps below need it.
struct CtGrid
{
  explicit CtGrid(vtkImageData* ct)
    : count(static_cast<std::size_t>(ct->GetNumberOfPoints())), data(ct->GetScalarPointer()),
      scalarType(ct->GetScalarType())
  {
    ct->GetDimensions(dims);
    ct->GetSpacing(spacing);
    voxelMm3 = std::abs(spacing[0] * spacing[1] * spacing[2]);
  }
  int dims[3];
  double spacing[3];
  double voxelMm3 = 0.0;
  std::size_t count;
  const void* data;
  int scalarType;
};

/// The working grid of about 1 mm the opening runs on: each working voxel
/// covers factor[a] CT voxels along axis a.
struct WorkingGrid
{
  explicit WorkingGrid(const CtGrid& ct)
  {
    for (int a = 0; a < 3; ++a)
    {
      factor[a] = std::max(1, static_cast<int>(std::floor(1.2 / std::abs(ct.spacing[a]))));
      dims[a] = (ct.dims[a] + factor[a] - 1) / factor[a];
      spacing[a] = std::abs(ct.spacing[a]) * factor[a];
    }
  }
  /// The working voxel holding CT voxel (i, j, k).
  std::int64_t index(int i, int j, int k) const
  {
    return (k / factor[2]) * (std::int64_t{dims[0]} * dims[1]) + std::int64_t{j / factor[1]} * dims[0] + i / factor[0];
  }
  int factor[3], dims[3];
  double spacing[3];
};

/// 1. Threshold: everything denser than air.
Mask::Pointer thresholdAboveAir(const CtGrid& ct, double thresholdHu)
{
  Mask::Pointer threshold = newMask(ct.dims, ct.spacing);
  switch (ct.scalarType)
  {
    vtkTemplateMacro(
      thresholdBuffer(static_cast<const VTK_TT*>(ct.data), ct.count, thresholdHu, threshold->GetBufferPointer()));
  default:
    throw std::invalid_argument("The CT volume has an unsupported voxel type.");
  }
  return threshold;
}

/// 2a. The opened body on the working grid: a working voxel is set only when
/// all the CT voxels it covers are (which erodes by at most one working
/// voxel more than the ball); eroded, its largest piece, dilated back by the
/// opening radius and the reconstruction margin.
Mask::Pointer openedBodyOnTheWorkingGrid(const Mask* threshold, const CtGrid& ct, const WorkingGrid& work,
                                         const SegmentationParameters& parameters, const Reporter& reporter)
{
  Mask::Pointer low = newMask(work.dims, work.spacing);
  unsigned char* lowData = low->GetBufferPointer();
  std::fill_n(lowData, low->GetLargestPossibleRegion().GetNumberOfPixels(), static_cast<unsigned char>(1));
  const unsigned char* t = threshold->GetBufferPointer();
  std::size_t n = 0;
  for (int k = 0; k < ct.dims[2]; ++k)
    for (int j = 0; j < ct.dims[1]; ++j)
      for (int i = 0; i < ct.dims[0]; ++i, ++n)
        if (!t[n])
          lowData[work.index(i, j, k)] = 0;

  using Erode = itk::BinaryErodeImageFilter<Mask, Mask, Kernel>;
  auto erode = Erode::New();
  erode->SetInput(low);
  erode->SetKernel(ballKernel(parameters.openingRadiusMm, work.spacing));
  erode->SetForegroundValue(1);
  erode->SetBackgroundValue(0);
  erode->SetBoundaryToForeground(true); // the body continues beyond the scanned slab
  runFilter(erode, reporter, 0.03, 0.15, "Separating the body from the table (erosion)");
  Mask::Pointer eroded = erode->GetOutput();
  eroded->DisconnectPipeline();
  erode = nullptr;
  low = nullptr;
  // The body's core is by far the largest piece left. Picking it before
  // the dilation that completes the opening means only it gets dilated.
  Mask::Pointer seed = largestComponent(eroded, reporter, 0.15, 0.2, "Finding the body (largest component)");
  eroded = nullptr;
  // Dilation by the opening radius completes the opening of the body; the
  // margin more restores detail the opening rounded off.
  using Dilate = itk::BinaryDilateImageFilter<Mask, Mask, Kernel>;
  auto dilate = Dilate::New();
  dilate->SetInput(seed);
  dilate->SetKernel(ballKernel(parameters.openingRadiusMm + parameters.reconstructionMarginMm, work.spacing));
  dilate->SetForegroundValue(1);
  dilate->SetBackgroundValue(0);
  dilate->SetBoundaryToForeground(false);
  runFilter(dilate, reporter, 0.2, 0.3, "Restoring the body's detail (dilation)");
  Mask::Pointer grown = dilate->GetOutput();
  grown->DisconnectPipeline();
  return grown;
}

/// 2c. Pieces the opening cut off the body (label 2 in @a threshold) are
/// small; the table and the holder are not. The small pieces come back as 1
/// (those not touching the body drop out with the largest component).
/// Returns the voxels put back.
std::size_t reattachSmallPieces(Mask* threshold, double voxelMm3, double maxPieceMm3, const Reporter& reporter)
{
  using LabelMap = itk::LabelMap<itk::LabelObject<std::uint32_t, 3>>;
  using ToLabelMap = itk::BinaryImageToLabelMapFilter<Mask, LabelMap>;
  auto pieces = ToLabelMap::New();
  pieces->SetInput(threshold);
  pieces->SetInputForegroundValue(2);
  pieces->SetFullyConnected(false);
  runFilter(pieces, reporter, 0.32, 0.4, "Restoring the body's detail (small pieces)");
  LabelMap* labels = pieces->GetOutput();
  std::size_t reattached = 0;
  for (std::size_t n = 0; n < labels->GetNumberOfLabelObjects(); ++n)
  {
    const auto* object = labels->GetNthLabelObject(n);
    if (object->Size() * voxelMm3 > maxPieceMm3)
      continue;
    for (std::size_t l = 0; l < object->GetNumberOfLines(); ++l)
    {
      const auto& line = object->GetLine(l);
      auto idx = line.GetIndex();
      for (itk::SizeValueType m = 0; m < line.GetLength(); ++m, ++idx[0])
        threshold->SetPixel(idx, 1);
    }
    reattached += object->Size();
  }
  return reattached;
}

/// 2. Opening, on a working grid of about 1 mm (the opening only has to
/// tell the body from the table, so full resolution would only cost time):
/// thin structures (the shells of the table and the head holder, the thin
/// contacts between them and the body, noise) vanish from @a threshold,
/// except small pieces the opening cut off the body. Returns the voxels of
/// those put back.
std::size_t separateTheBodyFromTheTable(Mask* threshold, const CtGrid& ct, const SegmentationParameters& parameters,
                                        const Reporter& reporter)
{
  const WorkingGrid work(ct);
  Mask::Pointer grown = openedBodyOnTheWorkingGrid(threshold, ct, work, parameters, reporter);

  // 2b. Back at full resolution: 1 = above the threshold and inside the
  // grown body, 2 = above the threshold but outside it (the table, the
  // holder, and whatever the opening cut off the body: the ear rims, the
  // nose tip).
  reporter.report(0.3, "Restoring the body's detail (full resolution)");
  const unsigned char* g = grown->GetBufferPointer();
  unsigned char* t = threshold->GetBufferPointer();
  std::size_t n = 0;
  for (int k = 0; k < ct.dims[2]; ++k)
    for (int j = 0; j < ct.dims[1]; ++j)
      for (int i = 0; i < ct.dims[0]; ++i, ++n)
        if (t[n])
          t[n] = g[work.index(i, j, k)] ? 1 : 2;
  grown = nullptr;

  const std::size_t reattached =
    parameters.maxReattachedPieceMm3 > 0
      ? reattachSmallPieces(threshold, ct.voxelMm3, parameters.maxReattachedPieceMm3, reporter)
      : 0;
  for (std::size_t i = 0; i < ct.count; ++i)
    t[i] = t[i] == 1 ? 1 : 0;
  return reattached;
}

/// 3. Internal air: per axial slice (the image axis closest to patient
/// superior), then the 3D cavities. Returns the note saying how much.
std::string fillInternalAir(Mask* body, vtkImageData* ct, const CtGrid& grid, const Reporter& reporter)
{
  int axial = 2;
  if (vtkMatrix3x3* direction = ct->GetDirectionMatrix())
  {
    double best = -1;
    for (int a = 0; a < 3; ++a)
      if (std::abs(direction->GetElement(2, a)) > best)
      {
        best = std::abs(direction->GetElement(2, a));
        axial = a;
      }
  }
  const std::size_t inSlices = fillHolesInSlices(body->GetBufferPointer(), grid.dims, axial, reporter, 0.58, 0.7);
  const auto [inCavities, cavities] = fillCavities3d(body, reporter, 0.7, 0.76);
  std::ostringstream note;
  note << "Internal air filled: " << formatVolume(inSlices * grid.voxelMm3) << " enclosed in axial slices, "
       << formatVolume(inCavities * grid.voxelMm3) << " in " << cavities << " closed cavities.";
  return note.str();
}

/// @a mask without its components (26-connected when @a fullyConnected)
/// smaller than @a lambdaMm3.
Mask::Pointer withoutSmallComponents(Mask* mask, bool fullyConnected, double lambdaMm3, const Reporter& reporter,
                                     double begin, double end, const std::string& step)
{
  using Opening = itk::BinaryShapeOpeningImageFilter<Mask>;
  auto opening = Opening::New();
  opening->SetInput(mask);
  opening->SetForegroundValue(1);
  opening->SetBackgroundValue(0);
  opening->SetFullyConnected(fullyConnected);
  opening->SetAttribute(Opening::LabelObjectType::PHYSICAL_SIZE);
  opening->SetLambda(lambdaMm3);
  runFilter(opening, reporter, begin, end, step);
  Mask::Pointer out = opening->GetOutput();
  out->DisconnectPipeline();
  return out;
}

/// 4b. The small cavities of @a bone filled: the small components of its
/// complement (6-connected, the complement of 26-connected bone).
Mask::Pointer withSmallCavitiesFilled(Mask* bone, std::size_t count, double maxHoleMm3, const Reporter& reporter)
{
  auto invert = [count](Mask* mask) {
    unsigned char* b = mask->GetBufferPointer();
    for (std::size_t i = 0; i < count; ++i)
      b[i] = 1 - b[i];
  };
  invert(bone);
  Mask::Pointer filled =
    withoutSmallComponents(bone, false, maxHoleMm3, reporter, 0.88, 0.97, "Filling small cavities in bone");
  invert(filled);
  return filled;
}

} // namespace

HeadMasks segmentHead(vtkImageData* ct, const SegmentationParameters& parameters, const ProgressCallback& progress)
{
  checkSegmentationInputs(ct, parameters);
  const Reporter reporter(progress);
  const CtGrid grid(ct);
  HeadMasks result;

  // 1. Threshold: everything denser than air.
  reporter.report(0.0, "Thresholding at the skin threshold");
  Mask::Pointer body = thresholdAboveAir(grid, parameters.skinThresholdHu);
  const std::size_t thresholdCount = countOnes(body->GetBufferPointer(), grid.count);
  if (thresholdCount == 0)
    throw std::invalid_argument("No voxel of the CT lies above the skin threshold (" +
                                std::to_string(parameters.skinThresholdHu) + " HU): is it in Hounsfield units?");

  // 2. The body apart from the table and the head holder: an opening, the
  // small pieces it cut off put back, the largest component.
  const std::size_t reattached =
    parameters.openingRadiusMm > 0 ? separateTheBodyFromTheTable(body, grid, parameters, reporter) : 0;
  body = largestComponent(body, reporter, 0.4, 0.58, "Finding the body (largest component)");
  const std::size_t bodyBeforeFill = countOnes(body->GetBufferPointer(), grid.count);
  {
    std::ostringstream note;
    note << "Body: largest component above " << parameters.skinThresholdHu << " HU after a "
         << parameters.openingRadiusMm << " mm opening, with the small pieces it cut off; "
         << formatVolume((thresholdCount - bodyBeforeFill) * grid.voxelMm3)
         << " above the threshold left out (table, head holder, clothes, noise); "
         << formatVolume(reattached * grid.voxelMm3) << " in small pieces put back.";
    result.notes.push_back(note.str());
  }

  // 3. Internal air filled.
  if (parameters.fillInternalAir)
    result.notes.push_back(fillInternalAir(body, ct, grid, reporter));
  const std::size_t bodyCount = countOnes(body->GetBufferPointer(), grid.count);
  result.notes.push_back("Body volume " + formatVolume(bodyCount * grid.voxelMm3) + ".");

  // 4. Bone: dense voxels inside the body, small islands removed, small
  // cavities filled.
  reporter.report(0.76, "Thresholding bone");
  Mask::Pointer bone = newMask(grid.dims, grid.spacing);
  switch (grid.scalarType)
  {
    vtkTemplateMacro(thresholdInside(static_cast<const VTK_TT*>(grid.data), body->GetBufferPointer(), grid.count,
                                     parameters.boneThresholdHu, bone->GetBufferPointer()));
  }
  const std::size_t boneRaw = countOnes(bone->GetBufferPointer(), grid.count);
  result.body = toVtkMask(body, ct);
  body = nullptr;
  if (parameters.minBoneIslandMm3 > 0)
    bone = withoutSmallComponents(bone, true, parameters.minBoneIslandMm3, reporter, 0.8, 0.88,
                                  "Removing small bone islands");
  const std::size_t boneKept = countOnes(bone->GetBufferPointer(), grid.count);
  if (parameters.maxBoneHoleMm3 > 0)
    bone = withSmallCavitiesFilled(bone, grid.count, parameters.maxBoneHoleMm3, reporter);
  const std::size_t boneCount = countOnes(bone->GetBufferPointer(), grid.count);
  {
    std::ostringstream note;
    note << "Bone: above " << parameters.boneThresholdHu << " HU inside the body, "
         << formatVolume(boneCount * grid.voxelMm3) << "; removed "
         << formatVolume((boneRaw - boneKept) * grid.voxelMm3) << " in islands under " << parameters.minBoneIslandMm3
         << " mm³, filled " << formatVolume((boneCount - boneKept) * grid.voxelMm3) << " of small cavities. "
         << "In a contrast CT, large contrast-filled vessels can exceed the bone "
            "threshold and count as bone.";
    result.notes.push_back(note.str());
  }
  result.bone = toVtkMask(bone, ct);
  reporter.report(1.0, "Segmentation done");
  return result;
}

} // namespace caps::seg
