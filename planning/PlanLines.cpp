#include "planning/PlanLines.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <vtkCellArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnsignedCharArray.h>

#include "planning/PlanDisplay.h"

namespace caps::planning {
namespace {

/// Builds the polydata: points, their "cut_point" numbers, lines and vertices.
class LineBuilder
{
public:
  LineBuilder(const SkinChart& chart, double lift) : chart_(chart), lift_(lift)
  {
    numbers_->SetName("cut_point");
    colours_->SetName("line_colour");
    colours_->SetNumberOfComponents(3);
  }
  /// The colour of the points added from now on.
  void setColour(const std::array<unsigned char, 3>& rgb) { colour_ = rgb; }

  /// The world point lift mm outside the skin above chart point p; -1 where there is no skin.
  vtkIdType add(const ChartPoint& p, int number)
  {
    const SkinPoint s = chart_.fromChart(p);
    const double r = chart_.skin().sample(s.theta, s.z);
    if (!std::isfinite(r))
      return -1;
    const Eigen::Vector3d w = chart_.skin().frame().toWorld(r + lift_, s.theta, s.z);
    numbers_->InsertNextValue(number);
    colours_->InsertNextTypedTuple(colour_.data());
    return points_->InsertNextPoint(w.x(), w.y(), w.z());
  }

  /// A polyline through the chart points, each segment sampled every step mm.
  void polyline(const std::vector<ChartPoint>& path, bool closed, double step)
  {
    std::vector<vtkIdType> ids;
    const std::size_t segments = closed ? path.size() : path.size() - 1;
    for (std::size_t i = 0; i < segments; ++i)
    {
      const ChartPoint& a = path[i];
      const ChartPoint& b = path[(i + 1) % path.size()];
      const int steps = std::max(1, int(std::ceil((b - a).norm() / step)));
      for (int k = 0; k < steps; ++k)
        ids.push_back(add(a + (b - a) * (double(k) / steps), -1));
    }
    ids.push_back(closed ? ids.front() : add(path.back(), -1));
    // A point without skin breaks the line rather than joining across the gap.
    std::vector<vtkIdType> run;
    const auto flush = [&] {
      if (run.size() >= 2)
        lines_->InsertNextCell(vtkIdType(run.size()), run.data());
      run.clear();
    };
    for (const vtkIdType id : ids)
      if (id < 0)
        flush();
      else
        run.push_back(id);
    flush();
  }

  void vertex(const ChartPoint& p, int number)
  {
    const vtkIdType id = add(p, number);
    if (id >= 0)
      vertices_->InsertNextCell(1, &id);
  }

  vtkSmartPointer<vtkPolyData> polyData() const
  {
    auto data = vtkSmartPointer<vtkPolyData>::New();
    data->SetPoints(points_);
    data->SetLines(lines_);
    data->SetVerts(vertices_);
    data->GetPointData()->AddArray(numbers_);
    data->GetPointData()->AddArray(colours_);
    return data;
  }

private:
  const SkinChart& chart_;
  double lift_;
  vtkNew<vtkPoints> points_;
  vtkNew<vtkCellArray> lines_;
  vtkNew<vtkCellArray> vertices_;
  vtkNew<vtkIntArray> numbers_;
  vtkNew<vtkUnsignedCharArray> colours_;
  std::array<unsigned char, 3> colour_ = kIncisionLineColour;
};

} // namespace

vtkSmartPointer<vtkPolyData> incisionLinesPolyData(const IncisionPlan& plan, const seg::RangeMap& skin, double lift,
                                                   double step)
{
  const SkinChart chart = plan.chart(skin);
  LineBuilder lines(chart, lift);
  const std::vector<ChartPoint> path = plan.chartPath(chart);
  if (path.size() >= 2)
    lines.polyline(path, false, step);
  // The hole border differs from the cut only where the sides were moved apart.
  if (plan.isExcision())
  {
    const fem::HoleLoop loop = plan.holeLoop(chart);
    std::vector<ChartPoint> border(loop.points.begin(), loop.points.end());
    if (border.size() >= 3)
      lines.polyline(border, true, step);
  }
  for (std::size_t i = 0; i < path.size(); ++i)
    lines.vertex(path[i], int(i));
  // The undermined regions' outlines, in the undermined skin's tint.
  lines.setColour({kUnderminedTint[0], kUnderminedTint[1], kUnderminedTint[2]});
  const seg::CylindricalFrame& frame = skin.frame();
  for (const UnderminedRegion& region : plan.underminedRegions())
  {
    std::vector<ChartPoint> outline;
    for (const Eigen::Vector2d& n : region)
    {
      const seg::CylindricalPoint c = frame.fromNormalized({1.0, n.x(), n.y()});
      outline.push_back(chart.toChart({c.theta, c.z}));
    }
    if (outline.size() >= 3)
      lines.polyline(outline, true, step);
  }
  return lines.polyData();
}

} // namespace caps::planning
