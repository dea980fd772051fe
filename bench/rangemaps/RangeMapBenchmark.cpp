// From a loaded 512 x 512 x 200 CT to the skin and bone range maps and the
// thickness maps (target: under 2 s on 2 cores), against the time
// VTK's flying edges takes to extract the skin isosurface of the same volume,
// measured in the same run. The CT is the top 200 slices of the embedded
// sample (512 x 512 x 295); the masks are a plain threshold + largest
// 6-connected component (body) and threshold inside the body (bone), made
// before the clock starts. Not a test: prints times and ratios only.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <functional>
#include <thread>
#include <vector>

#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "segmentation/CtReader.h"
#include "segmentation/HeadAxis.h"
#include "segmentation/RangeMapBuilder.h"
#include "segmentation/RangeMapImageGeometry.h"
#include "segmentation/Thickness.h"
#include "bench/BestOf.h"

namespace fs = std::filesystem;
using namespace caps::seg;

using caps::bench::secondsOf;

namespace {

/// The last `slices` slices (the superior end for this head-first series) as a new image.
vtkSmartPointer<vtkImageData> topSlices(vtkImageData* ct, int slices)
{
  int dims[3];
  ct->GetDimensions(dims);
  slices = std::min(slices, dims[2]);
  const int first = dims[2] - slices;
  ImageGeometry g = ImageGeometry::of(ct);
  g.origin = g.indexToWorld(Eigen::Vector3d(g.extent[0], g.extent[2], g.extent[4] + first));
  g.extent = {0, dims[0] - 1, 0, dims[1] - 1, 0, slices - 1};
  auto out = vtkSmartPointer<vtkImageData>::New();
  g.applyTo(out);
  out->AllocateScalars(ct->GetScalarType(), 1);
  const std::size_t slice = static_cast<std::size_t>(dims[0]) * dims[1] * ct->GetScalarSize();
  std::memcpy(out->GetScalarPointer(), static_cast<const char*>(ct->GetScalarPointer()) + first * slice,
              slice * slices);
  return out;
}

template <typename T> void makeMasks(const T* hu, const int dims[3], unsigned char* body, unsigned char* bone)
{
  const std::size_t n = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  std::vector<int> label(n, 0);
  int best = 0, bestLabel = 0, next = 0;
  const std::ptrdiff_t sy = dims[0], sz = static_cast<std::ptrdiff_t>(dims[0]) * dims[1];
  std::vector<std::size_t> stack;
  for (std::size_t seed = 0; seed < n; ++seed)
  {
    if (label[seed] || static_cast<double>(hu[seed]) < -400.0)
      continue;
    ++next;
    int size = 0;
    stack.assign(1, seed);
    label[seed] = next;
    while (!stack.empty())
    {
      const std::size_t o = stack.back();
      stack.pop_back();
      ++size;
      const int i = static_cast<int>(o % dims[0]), j = static_cast<int>((o / dims[0]) % dims[1]),
                k = static_cast<int>(o / sz);
      const std::ptrdiff_t step[6] = {-1, 1, -sy, sy, -sz, sz};
      const bool ok[6] = {i > 0, i<dims[0] - 1, j> 0, j<dims[1] - 1, k> 0, k < dims[2] - 1};
      for (int d = 0; d < 6; ++d)
        if (ok[d])
        {
          const std::size_t q = o + step[d];
          if (!label[q] && static_cast<double>(hu[q]) >= -400.0)
          {
            label[q] = next;
            stack.push_back(q);
          }
        }
    }
    if (size > best)
    {
      best = size;
      bestLabel = next;
    }
  }
  for (std::size_t o = 0; o < n; ++o)
  {
    body[o] = label[o] == bestLabel;
    bone[o] = body[o] && static_cast<double>(hu[o]) >= 250.0;
  }
}

} // namespace

int main(int argc, char** argv)
{
  const fs::path folder = argc > 1 ? fs::path(argv[1]) : fs::path(CAPS_SAMPLE_CT);
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 3;
  const int threads = argc > 3 ? std::atoi(argv[3]) : 2;

  std::printf("Range map benchmark on %s (best of %d, %d threads, %u cores seen)\n", folder.c_str(), repeats, threads,
              std::thread::hardware_concurrency());
  const CtVolume volume = readCtVolume(folder);
  vtkSmartPointer<vtkImageData> ct = topSlices(volume.image, 200);
  int dims[3];
  ct->GetDimensions(dims);
  std::printf("CT %d x %d x %d, %s, spacing %.3f x %.3f x %.3f mm\n", dims[0], dims[1], dims[2],
              ct->GetScalarTypeAsString(), ct->GetSpacing()[0], ct->GetSpacing()[1], ct->GetSpacing()[2]);

  auto body = vtkSmartPointer<vtkImageData>::New();
  auto bone = vtkSmartPointer<vtkImageData>::New();
  for (vtkImageData* m : {body.Get(), bone.Get()})
  {
    ImageGeometry::of(ct).applyTo(m);
    m->AllocateScalars(VTK_UNSIGNED_CHAR, 1);
  }
  switch (ct->GetScalarType())
  {
    vtkTemplateMacro(makeMasks(static_cast<const VTK_TT*>(ct->GetScalarPointer()), dims,
                               static_cast<unsigned char*>(body->GetScalarPointer()),
                               static_cast<unsigned char*>(bone->GetScalarPointer())));
  }

  HeadAxisFit fit;
  SkinBoneRangeMaps maps;
  RangeMap radial, normal;
  RangeMapBuildOptions buildOptions;
  buildOptions.threads = threads;
  NormalThicknessOptions thicknessOptions;
  thicknessOptions.threads = threads;
  double tFit = 0, tMaps = 0, tThickness = 0;
  const double total = secondsOf(
    [&] {
      const auto t0 = std::chrono::steady_clock::now();
      fit = fitHeadAxis(body);
      const auto t1 = std::chrono::steady_clock::now();
      maps = buildRangeMaps(ct, body, bone, fit.frame, buildOptions);
      const auto t2 = std::chrono::steady_clock::now();
      radial = radialThickness(maps.skin, maps.bone);
      normal = normalThickness(maps.skin, maps.bone, thicknessOptions);
      const auto t3 = std::chrono::steady_clock::now();
      tFit = std::chrono::duration<double>(t1 - t0).count();
      tMaps = std::chrono::duration<double>(t2 - t1).count();
      tThickness = std::chrono::duration<double>(t3 - t2).count();
    },
    repeats);

  vtkIdType triangles = 0;
  const double flyingEdges = secondsOf(
    [&] {
      auto fe = vtkSmartPointer<vtkFlyingEdges3D>::New();
      fe->SetInputData(ct);
      fe->SetValue(0, -400.0);
      fe->ComputeNormalsOff();
      fe->ComputeGradientsOff();
      fe->ComputeScalarsOff();
      fe->Update();
      triangles = fe->GetOutput()->GetNumberOfPolys();
    },
    repeats);

  const auto& f = fit.frame;
  std::printf("axis through (%.1f, %.1f, %.1f) along (%.3f, %.3f, %.3f), z %.1f..%.1f mm, %d slices, rms %.2f mm\n",
              f.origin().x(), f.origin().y(), f.origin().z(), f.direction().x(), f.direction().y(), f.direction().z(),
              f.zMin(), f.zMax(), fit.slicesUsed, fit.rmsResidual);
  std::printf("maps %d x %d: skin %zu finite (%zu at the mask edge), bone %zu finite (%zu at the mask edge)\n",
              f.nTheta(), f.nZ(), maps.skin.validCount(), maps.skinFromMaskEdge, maps.bone.validCount(),
              maps.boneFromMaskEdge);
  for (const auto& [name, map] : {std::pair<const char*, const RangeMap*>{"radial", &radial}, {"normal", &normal}})
  {
    const ThicknessStatistics s = thicknessStatistics(*map);
    std::printf("%s thickness: %zu samples, p5 %.1f, median %.1f, p95 %.1f, mean %.1f mm\n", name, s.count, s.p5,
                s.median, s.p95, s.mean);
  }
  std::printf("frame fit          %8.3f s\n", tFit);
  std::printf("skin + bone maps   %8.3f s\n", tMaps);
  std::printf("thickness (both)   %8.3f s\n", tThickness);
  std::printf("total              %8.3f s   (target < 2 s on 2 cores)\n", total);
  std::printf("vtkFlyingEdges3D   %8.3f s   (skin isosurface at -400 HU, %lld triangles)\n", flyingEdges,
              static_cast<long long>(triangles));
  std::printf("ratio total / flying edges: %.2f\n", total / flyingEdges);
  return 0;
}
