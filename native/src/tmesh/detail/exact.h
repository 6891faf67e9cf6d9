// Exact integer and rational arithmetic for the motorcycle tracer (internal).
//
// Coordinates are int64 fixed-point values (doubled, so that midpoints stay integral). Derived
// quantities (positions where an isoline crosses a triangle edge, travel times) are rationals
// with 128-bit numerators; comparisons never overflow (continued-fraction fallback).
#pragma once
#include <array>
#include <cstdint>
#include <cstdlib>

namespace qgp::tmesh_detail {

using i128 = __int128;
using P2 = std::array<int64_t, 2>;  // a grid point or integer vector

inline int sign(i128 x) { return (x > 0) - (x < 0); }
inline i128 abs128(i128 x) { return x < 0 ? -x : x; }

// floor(a / b) for b > 0.
inline i128 floor_div(i128 a, i128 b) {
  i128 q = a / b;
  if ((a % b != 0) && (a < 0)) --q;
  return q;
}

inline i128 gcd128(i128 a, i128 b) {
  a = abs128(a);
  b = abs128(b);
  while (b != 0) {
    const i128 t = a % b;
    a = b;
    b = t;
  }
  return a;
}

// Sign of a/b - c/d for b, d > 0, exact for all 128-bit inputs.
inline int compare_fractions(i128 a, i128 b, i128 c, i128 d) {
  const i128 kSmall = i128(1) << 62;
  if (abs128(a) < kSmall && b < kSmall && abs128(c) < kSmall && d < kSmall) return sign(a * d - c * b);
  // Continued fractions: compare integer parts, then the reciprocals of the remainders.
  int flip = 1;
  for (;;) {
    const i128 qa = floor_div(a, b), qc = floor_div(c, d);
    if (qa != qc) return flip * (qa < qc ? -1 : 1);
    const i128 ra = a - qa * b, rc = c - qc * d;  // 0 <= r < denominator
    if (ra == 0 || rc == 0) return flip * ((ra == 0 ? 0 : 1) - (rc == 0 ? 0 : 1));
    // a/b - c/d has the sign of d/rc - b/ra.
    a = b, b = ra;
    c = d, d = rc;
    flip = -flip;
  }
}

// A rational number num/den with den > 0 (not necessarily reduced).
struct Rational {
  i128 num = 0, den = 1;
  Rational() = default;
  Rational(i128 n) : num(n), den(1) {}  // NOLINT: integers convert implicitly
  Rational(i128 n, i128 d) : num(d < 0 ? -n : n), den(d < 0 ? -d : d) {}
  double to_double() const {
    return static_cast<double>(static_cast<long double>(num) / static_cast<long double>(den));
  }
  Rational reduced() const {
    const i128 g = gcd128(num, den);
    return g > 1 ? Rational(num / g, den / g) : *this;
  }
};
inline int compare(const Rational& x, const Rational& y) { return compare_fractions(x.num, x.den, y.num, y.den); }
inline bool operator<(const Rational& x, const Rational& y) { return compare(x, y) < 0; }
inline bool operator>(const Rational& x, const Rational& y) { return compare(x, y) > 0; }
inline bool operator<=(const Rational& x, const Rational& y) { return compare(x, y) <= 0; }
inline bool operator>=(const Rational& x, const Rational& y) { return compare(x, y) >= 0; }
inline bool operator==(const Rational& x, const Rational& y) { return compare(x, y) == 0; }
inline bool operator!=(const Rational& x, const Rational& y) { return compare(x, y) != 0; }
// x + k for an integer k, and sign flips: exact without growing the denominator.
inline Rational add_int(const Rational& x, i128 k) { return Rational(x.num + k * x.den, x.den); }
inline Rational negate(const Rational& x) { return Rational(-x.num, x.den); }

inline i128 cross(const P2& a, const P2& b) { return i128(a[0]) * b[1] - i128(a[1]) * b[0]; }
inline i128 dot(const P2& a, const P2& b) { return i128(a[0]) * b[0] + i128(a[1]) * b[1]; }
inline P2 sub(const P2& a, const P2& b) { return {a[0] - b[0], a[1] - b[1]}; }
inline int orient(const P2& a, const P2& b, const P2& c) { return sign(cross(sub(b, a), sub(c, a))); }

// The four cardinal directions: 0 = +u, 1 = +v, 2 = -u, 3 = -v.
inline P2 cardinal(int d) {
  switch (d & 3) {
    case 0: return {1, 0};
    case 1: return {0, 1};
    case 2: return {-1, 0};
    default: return {0, -1};
  }
}
inline int axis_of(int d) { return d & 1; }              // moving coordinate of direction d
inline int fixed_axis_of(int d) { return 1 - (d & 1); }  // coordinate that stays constant
inline int sense_of(int d) { return (d & 3) < 2 ? 1 : -1; }

// Cardinal direction of a vector that is exactly axis-aligned, or -1.
inline int exact_cardinal(const P2& e) {
  if (e[1] == 0 && e[0] > 0) return 0;
  if (e[0] == 0 && e[1] > 0) return 1;
  if (e[1] == 0 && e[0] < 0) return 2;
  if (e[0] == 0 && e[1] < 0) return 3;
  return -1;
}
// First cardinal direction at or counter-clockwise after e (e != 0).
inline int cardinal_at_or_after(const P2& e) {
  const int exact = exact_cardinal(e);
  if (exact >= 0) return exact;
  if (e[0] > 0 && e[1] > 0) return 1;
  if (e[0] < 0 && e[1] > 0) return 2;
  if (e[0] < 0 && e[1] < 0) return 3;
  return 0;
}
// Last cardinal direction at or clockwise before e.
inline int cardinal_at_or_before(const P2& e) {
  const int exact = exact_cardinal(e);
  return exact >= 0 ? exact : (cardinal_at_or_after(e) + 3) & 3;
}
// Cardinal direction closest in angle to e; at exactly 45 degrees the counter-clockwise one.
inline int nearest_cardinal(const P2& e) {
  const i128 ax = abs128(e[0]), ay = abs128(e[1]);
  if (ax > ay) return e[0] > 0 ? 0 : 2;
  if (ay > ax) return e[1] > 0 ? 1 : 3;
  return cardinal_at_or_after(e);
}
// Is cardinal d in the half-open counter-clockwise angle [a, b) of a corner with orient > 0?
inline bool cardinal_in_corner(int d, const P2& a, const P2& b) {
  const P2 dv = cardinal(d);
  const i128 ca = cross(a, dv);
  if (ca == 0) return dot(a, dv) > 0;  // on the ray of a
  return ca > 0 && cross(dv, b) > 0;
}

}  // namespace qgp::tmesh_detail
