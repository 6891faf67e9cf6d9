#include "seamless_map/orientation.h"

#include <gmpxx.h>

#include <cmath>

namespace qgp {

int orient2d_sign(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double l = (b.x() - a.x()) * (c.y() - a.y());
  const double r = (b.y() - a.y()) * (c.x() - a.x());
  const double det = l - r;
  // Shewchuk's bound for this evaluation order: (3 + 16 eps) eps (|l| + |r|), eps = 2^-53.
  const double bound = 3.3306690738754716e-16 * (std::abs(l) + std::abs(r));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  if (!std::isfinite(det)) return 0;
  const mpq_class ax(a.x()), ay(a.y()), bx(b.x()), by(b.y()), cx(c.x()), cy(c.y());
  const mpq_class exact = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  return sgn(exact);
}

}  // namespace qgp
