#include "fem/ElementGeometry.h"

#include <Eigen/LU>

#include <cmath>
#include <sstream>

namespace caps::fem {

void evaluateGeometry(const ElementShape& shape, const ElementCoordinates& x, const Eigen::Vector3d& rst,
                      int elementIndex, PointGeometry& out, bool check)
{
  shape.evaluate(rst, out.h, out.dhNatural);
  out.jacobian.noalias() = out.dhNatural.transpose() * x;
  out.world.noalias() = x.transpose() * out.h;
  out.detJ = out.jacobian.determinant();
  const double scale = out.jacobian.row(0).norm() * out.jacobian.row(1).norm() * out.jacobian.row(2).norm();
  const bool finite = std::isfinite(out.detJ);
  if (check && (!finite || out.detJ <= 0.0 || out.detJ < kMinScaledJacobian * scale))
  {
    std::ostringstream m;
    m.precision(4);
    m << "element " << elementIndex << " is ";
    if (!finite)
      m << "undefined (non-finite Jacobian)";
    else if (out.detJ < 0.0)
      m << "inverted (det J = " << out.detJ << " mm^3 < 0)";
    else
      m << "collapsed or badly distorted (det J = " << out.detJ << " mm^3, scaled Jacobian "
        << (scale > 0.0 ? out.detJ / scale : 0.0) << ")";
    m << " at natural point (r, s, t) = (" << rst[0] << ", " << rst[1] << ", " << rst[2] << "), world (" << out.world[0]
      << ", " << out.world[1] << ", " << out.world[2] << ") mm; check its node order (" << shape.numberingName()
      << ") and positions";
    throw ElementError(elementIndex, m.str());
  }
  if (finite && out.detJ != 0.0)
  {
    out.dhWorld.noalias() = out.dhNatural * out.jacobian.inverse().transpose();
  }
  else
  {
    out.dhWorld.setZero();
  }
}

} // namespace caps::fem
