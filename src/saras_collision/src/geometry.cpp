// Exact capsule / sphere / box distances. See include/saras_collision/geometry.h for the
// definitions and the return codes; the derivations are summarised next to each function.
#include "saras_collision/geometry.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace saras_collision
{
namespace
{
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Squared length below which a capsule axis is treated as a point [m^2] (length < 1e-15 m).
constexpr double kDegenerateLength2 = 1e-30;

inline bool validRadius(double r)
{
  return std::isfinite(r) && r >= 0.0;
}

/// All coordinates finite: NaN and +-inf propagate through the sum (finite values whose sum
/// overflows, > 1e307 m, are rejected too, which is intended).
inline bool allFinite(const Eigen::Vector3d& a, const Eigen::Vector3d& b)
{
  return std::isfinite((a + b).sum() + (a - b).sum());
}

// std::min/std::max compile to branch-free minsd/maxsd (random inputs mispredict branches).
inline double clamp01(double x)
{
  return std::min(std::max(x, 0.0), 1.0);
}

inline double clampTo(double x, double h)
{
  return std::min(std::max(x, -h), h);
}

DistanceResult invalid(int code)
{
  DistanceResult r;
  r.code = code;
  r.distance = kNaN;
  r.point1 = Eigen::Vector3d::Constant(kNaN);
  r.point2 = Eigen::Vector3d::Constant(kNaN);
  r.normal = Eigen::Vector3d::Constant(kNaN);
  return r;
}

/// Any unit vector orthogonal to a non-zero @p v.
Eigen::Vector3d anyPerpendicular(const Eigen::Vector3d& v)
{
  Eigen::Vector3d other = std::abs(v.x()) <= std::abs(v.y()) && std::abs(v.x()) <= std::abs(v.z()) ?
                              Eigen::Vector3d::UnitX() :
                              (std::abs(v.y()) <= std::abs(v.z()) ? Eigen::Vector3d::UnitY() :
                                                                    Eigen::Vector3d::UnitZ());
  return v.cross(other).normalized();
}

int classify(double distance, bool parallel)
{
  if (distance < -kTangentTolerance)
    return kIntersecting;
  if (distance <= kTangentTolerance)
    return kTangent;
  return parallel ? kParallel : kSeparated;
}

/// min over t in [0,1] of G(t) = max_i(|a_i + t d_i| - h_i) (see capsuleBox), with its argmin.
/// @param t_hint an extra candidate
double minimumDepth(const Eigen::Vector3d& a, const Eigen::Vector3d& d, const Eigen::Vector3d& h, double t_hint,
                    double* argmin = nullptr)
{
  auto depth = [&](double tt) {
    double g = -std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i)
      g = std::max(g, std::abs(a[i] + tt * d[i]) - h[i]);
    return g;
  };
  double best_t = 0.0, best = depth(0.0);
  auto consider = [&](double tt) {
    if (!(tt >= 0.0 && tt <= 1.0))
      return;
    const double g = depth(tt);
    if (g < best)
    {
      best = g;
      best_t = tt;
    }
  };
  consider(1.0);
  consider(t_hint);
  // Pieces: sigma * (a_i + t d_i) - h_i, for i in {0,1,2}, sigma in {+1,-1}; the minimum of
  // their maximum is at an end-point or at a crossing of two pieces.
  for (int p = 0; p < 6; ++p)
  {
    const int i = p / 2;
    const double si = p % 2 == 0 ? 1.0 : -1.0;
    for (int q = p + 1; q < 6; ++q)
    {
      const int j = q / 2;
      const double sj = q % 2 == 0 ? 1.0 : -1.0;
      const double den = si * d[i] - sj * d[j];
      if (den == 0.0)
        continue;
      consider((h[i] - h[j] - si * a[i] + sj * a[j]) / den);
    }
  }
  if (argmin != nullptr)
    *argmin = best_t;
  return best;
}
}  // namespace

const char* codeName(int code)
{
  switch (code)
  {
    case kInvalidInput:
      return "invalid_input";
    case kInvalidBox:
      return "invalid_box";
    case kIntersecting:
      return "intersecting";
    case kTangent:
      return "tangent";
    case kSeparated:
      return "separated";
    case kParallel:
      return "parallel";
    default:
      return "unknown";
  }
}

int makeBox(const Eigen::Vector3d vertices[], double relative_tolerance, OrientedBox& box)
{
  double sum = 0.0;  // NaN / inf propagate
  for (int i = 0; i < 8; ++i)
    sum += vertices[i].sum();
  if (!std::isfinite(sum))
    return kInvalidInput;
  if (!(relative_tolerance >= 0.0) || !std::isfinite(relative_tolerance))
    return kInvalidInput;
  const Eigen::Vector3d& v0 = vertices[0];
  const Eigen::Vector3d ex = vertices[1] - v0;
  const Eigen::Vector3d ey = vertices[4] - v0;
  const Eigen::Vector3d ez = vertices[3] - v0;
  const double lx2 = ex.squaredNorm(), ly2 = ey.squaredNorm(), lz2 = ez.squaredNorm();
  const double diag2 = lx2 + ly2 + lz2;
  if (!(diag2 > 0.0))
    return kInvalidBox;
  const double tol2 = relative_tolerance * relative_tolerance * diag2;
  const double rt2 = relative_tolerance * relative_tolerance;
  if (lx2 <= tol2 || ly2 <= tol2 || lz2 <= tol2)
    return kInvalidBox;  // flat or degenerate
  const double xy = ex.dot(ey), xz = ex.dot(ez), yz = ey.dot(ez);
  if (xy * xy > rt2 * lx2 * ly2 || xz * xz > rt2 * lx2 * lz2 || yz * yz > rt2 * ly2 * lz2)
    return kInvalidBox;  // not rectangular
  if ((vertices[2] - v0 - ex - ez).squaredNorm() > tol2 || (vertices[5] - v0 - ex - ey).squaredNorm() > tol2 ||
      (vertices[6] - v0 - ex - ey - ez).squaredNorm() > tol2 || (vertices[7] - v0 - ey - ez).squaredNorm() > tol2)
    return kInvalidBox;  // wrong order or not a box
  const double lx = std::sqrt(lx2), ly = std::sqrt(ly2), lz = std::sqrt(lz2);

  // Orthonormal frame (Gram-Schmidt keeps x exact; the residual non-orthogonality is within
  // the tolerance). The handedness of the vertex order is kept.
  const Eigen::Vector3d x = ex / lx;
  const Eigen::Vector3d y = (ey - ey.dot(x) * x).normalized();
  Eigen::Vector3d z = x.cross(y);
  if (z.dot(ez) < 0.0)
    z = -z;
  box.center = 0.5 * (v0 + vertices[6]);  // midpoint of the main diagonal
  box.axes.col(0) = x;
  box.axes.col(1) = y;
  box.axes.col(2) = z;
  box.half = Eigen::Vector3d(lx, ly, lz) * 0.5;
  box.bounding_radius = box.half.norm();
  return kSeparated;
}

void boxVertices(const OrientedBox& box, Eigen::Vector3d vertices[])
{
  const Eigen::Vector3d x = box.axes.col(0) * (2.0 * box.half.x());
  const Eigen::Vector3d y = box.axes.col(1) * (2.0 * box.half.y());
  const Eigen::Vector3d z = box.axes.col(2) * (2.0 * box.half.z());
  const Eigen::Vector3d v0 = box.center - 0.5 * (x + y + z);
  vertices[0] = v0;
  vertices[1] = v0 + x;
  vertices[2] = v0 + x + z;
  vertices[3] = v0 + z;
  vertices[4] = v0 + y;
  vertices[5] = v0 + x + y;
  vertices[6] = v0 + x + y + z;
  vertices[7] = v0 + y + z;
}

// Segment-segment: minimise |p1 + s d1 - p3 - t d2|^2 over [0,1]^2 (convex quadratic).
// Interior stationary point from the 2x2 normal equations (denominator |d1 x d2|^2, taken from
// the cross product when nearly parallel to avoid cancellation), clamped; then t is
// re-optimised for s and, if clamped, s for t.
// Degenerate axes reduce to point-segment projections.
DistanceResult capsuleCapsule(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r1,
                              const Eigen::Vector3d& p3, const Eigen::Vector3d& p4, double r2)
{
  if (!allFinite(p1, p2) || !allFinite(p3, p4) || !validRadius(r1) || !validRadius(r2))
    return invalid(kInvalidInput);
  const Eigen::Vector3d d1 = p2 - p1;
  const Eigen::Vector3d d2 = p4 - p3;
  const Eigen::Vector3d w = p1 - p3;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(w);
  double s = 0.0, t = 0.0;
  bool parallel = false;
  const bool point1 = a <= kDegenerateLength2;
  const bool point2 = e <= kDegenerateLength2;
  if (point1 && point2)
  {
    s = t = 0.0;
  }
  else if (point1)
  {
    t = clamp01(f / e);
  }
  else
  {
    const double c = d1.dot(w);
    if (point2)
    {
      s = clamp01(-c / a);
    }
    else
    {
      const double b = d1.dot(d2);
      // |d1 x d2|^2 = a e - b^2; near parallel the difference cancels, so it is then recomputed
      // from the cross product (relative error of a e - b^2 ~ 1e-16 / 1e-3 otherwise).
      double denom = a * e - b * b;
      if (denom < 1e-3 * a * e)
        denom = d1.cross(d2).squaredNorm();
      if (denom > kParallelSin2 * a * e)
      {
        s = clamp01((b * f - c * e) / denom);
      }
      else
      {
        parallel = true;
        s = 0.0;  // any s is optimal up to the clamping of t, fixed below
      }
      const double inv_a = 1.0 / a;  // independent of the chain above: overlaps with it
      t = (b * s + f) / e;
      if (t < 0.0)
      {
        t = 0.0;
        s = clamp01(-c * inv_a);
      }
      else if (t > 1.0)
      {
        t = 1.0;
        s = clamp01((b - c) * inv_a);
      }
    }
  }
  const Eigen::Vector3d q1 = p1 + s * d1;
  const Eigen::Vector3d q2 = p3 + t * d2;
  const Eigen::Vector3d v = q1 - q2;
  const double axis = v.norm();

  DistanceResult out;
  out.distance = axis - r1 - r2;
  out.code = classify(out.distance, parallel);
  if (axis > 0.0)
    out.normal = v * (1.0 / axis);
  else if (!point1 && !point2 && !parallel)
    out.normal = d1.cross(d2).normalized();
  else if (!point1)
    out.normal = anyPerpendicular(d1);
  else if (!point2)
    out.normal = anyPerpendicular(d2);
  else
    out.normal = Eigen::Vector3d::UnitZ();

  if (out.code == kIntersecting)
  {
    out.point1 = q1;  // witnesses: closest points of the axes
    out.point2 = q2;
  }
  else
  {
    out.point1 = q1 - r1 * out.normal;
    out.point2 = q2 + r2 * out.normal;
  }
  return out;
}

// Capsule-box, in the box frame (centre c, axes R, half extents h). With x(t) = a + t d the
// axis in box coordinates, the squared axis-box distance is
//   F(t) = sum_i phi_i(x_i(t)),  phi_i(u) = (|u| - h_i)_+^2,
// convex, C1 and piecewise quadratic; F'(t)/2 = sum_i d_i (x_i - clamp(x_i, -h_i, h_i)) is
// continuous, non-decreasing and piecewise linear with breakpoints where x_i(t) = +-h_i.
// Walking the (at most 6) sorted breakpoints locates the zero of F' exactly by linear
// interpolation inside one piece. If the axis reaches the box (F = 0), the signed distance
// uses G(t) = max_i(|x_i(t)| - h_i), which equals the box's signed distance function where it
// is <= 0; G is convex piecewise linear, so its minimum on [0,1] is at an end-point or at a
// crossing of two of its 6 linear pieces (kinks of |.| included).
DistanceResult capsuleBox(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r, const OrientedBox& box)
{
  if (!allFinite(p1, p2) || !validRadius(r))
    return invalid(kInvalidInput);
  const Eigen::Matrix3d& R = box.axes;
  const Eigen::Vector3d& h = box.half;
  const Eigen::Vector3d a = R.transpose() * (p1 - box.center);
  if (p1 == p2)
  {
    // Sphere: closest box point = clamped centre (the general path below gives the same).
    const Eigen::Vector3d q(clampTo(a[0], h[0]), clampTo(a[1], h[1]), clampTo(a[2], h[2]));
    const Eigen::Vector3d v = a - q;
    const double axis2 = v.squaredNorm();
    if (axis2 > kTangentTolerance * kTangentTolerance)
    {
      const double axis = std::sqrt(axis2);
      DistanceResult out;
      out.distance = axis - r;
      out.code = classify(out.distance, false);
      const Eigen::Vector3d v_world = R * v;
      out.normal = v_world * (1.0 / axis);
      out.point2 = p1 - v_world;
      out.point1 = out.code == kIntersecting ? p1 : Eigen::Vector3d(p1 - r * out.normal);
      return out;
    }
  }
  const Eigen::Vector3d d = R.transpose() * (p2 - p1);  // exactly zero for a sphere

  auto slope = [&](double t) {
    double g = 0.0;
    for (int i = 0; i < 3; ++i)
    {
      const double x = a[i] + t * d[i];
      g += d[i] * (x - clampTo(x, h[i]));
    }
    return g;
  };

  double t = 0.0;
  const double g0 = d.isZero(0.0) ? 0.0 : slope(0.0);  // sphere: t = 0
  if (g0 < 0.0)
  {
    const double g1 = slope(1.0);
    if (g1 <= 0.0)
    {
      t = 1.0;
    }
    else
    {
      double bp[7];
      int n = 0;
      for (int i = 0; i < 3; ++i)
      {
        if (d[i] == 0.0)
          continue;
        const double ta = (-h[i] - a[i]) / d[i];
        const double tb = (h[i] - a[i]) / d[i];
        if (ta > 0.0 && ta < 1.0)
          bp[n++] = ta;
        if (tb > 0.0 && tb < 1.0)
          bp[n++] = tb;
      }
      for (int i = 1; i < n; ++i)  // insertion sort of <= 6 values
      {
        const double key = bp[i];
        int j = i - 1;
        for (; j >= 0 && bp[j] > key; --j)
          bp[j + 1] = bp[j];
        bp[j + 1] = key;
      }
      bp[n++] = 1.0;
      double t_prev = 0.0, g_prev = g0;
      t = 1.0;
      for (int k = 0; k < n; ++k)
      {
        const double g = k + 1 == n ? g1 : slope(bp[k]);
        if (g >= 0.0)
        {
          t = t_prev + (-g_prev) * (bp[k] - t_prev) / (g - g_prev);
          t = std::min(std::max(t, t_prev), bp[k]);
          break;
        }
        t_prev = bp[k];
        g_prev = g;
      }
    }
  }

  DistanceResult out;
  Eigen::Vector3d x = a + t * d;
  Eigen::Vector3d q(clampTo(x[0], h[0]), clampTo(x[1], h[1]), clampTo(x[2], h[2]));
  const Eigen::Vector3d v = x - q;
  const double axis = v.norm();
  // Entering the box leaves x(t*) on its boundary up to rounding: below the tangent tolerance
  // the depth computation below decides (it returns >= 0 only if the axis merely touches).
  if (axis > kTangentTolerance || (axis > 0.0 && minimumDepth(a, d, h, t) >= 0.0))
  {
    out.distance = axis - r;
    out.code = classify(out.distance, false);
    const Eigen::Vector3d v_world = R * v;  // axis point - box point, world
    out.normal = v_world * (1.0 / axis);
    const Eigen::Vector3d axis_point = p1 + t * (p2 - p1);
    out.point2 = axis_point - v_world;
    out.point1 = out.code == kIntersecting ? axis_point : Eigen::Vector3d(axis_point - r * out.normal);
    return out;
  }

  // The axis reaches the box.
  double best_t = t;
  const double best = minimumDepth(a, d, h, t, &best_t);
  x = a + best_t * d;
  const Eigen::Vector3d axis_point = p1 + best_t * (p2 - p1);
  out.distance = std::min(best, 0.0) - r;
  out.code = classify(out.distance, false);
  int face = 0;
  double face_g = std::abs(x[0]) - h[0];
  for (int i = 1; i < 3; ++i)
  {
    const double g = std::abs(x[i]) - h[i];
    if (g > face_g)
    {
      face_g = g;
      face = i;
    }
  }
  const double sign = x[face] < 0.0 ? -1.0 : 1.0;
  out.normal = R.col(face) * sign;
  if (out.code == kIntersecting)
  {
    Eigen::Vector3d on_face = x;
    on_face[face] = sign * h[face];
    out.point1 = axis_point;
    out.point2 = box.center + R * on_face;
  }
  else
  {
    out.point1 = axis_point;  // tangent: zero radius axis touching the box
    out.point2 = axis_point;
  }
  return out;
}

int dist_capsule_to_capsule(const Eigen::Vector3d& P1, const Eigen::Vector3d& P2, const Eigen::Vector3d& P3,
                            const Eigen::Vector3d& P4, double r1, double r2, double& distance,
                            Eigen::Vector3d& point_on_capsule1, Eigen::Vector3d& point_on_capsule2)
{
  const DistanceResult res = capsuleCapsule(P1, P2, r1, P3, P4, r2);
  distance = res.distance;
  point_on_capsule1 = res.point1;
  point_on_capsule2 = res.point2;
  return res.code;
}

int dist_capsule_to_parallelepiped(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                                   const Eigen::Vector3d vertices[], double r, double& distance,
                                   Eigen::Vector3d& point_on_capsule, Eigen::Vector3d& point_on_parall)
{
  OrientedBox box;
  const int built = vertices == nullptr ? kInvalidInput : makeBox(vertices, kBoxRelativeTolerance, box);
  DistanceResult res = built == kSeparated ? capsuleBox(p1, p2, r, box) : invalid(built);
  distance = res.distance;
  point_on_capsule = res.point1;
  point_on_parall = res.point2;
  return res.code;
}

int dist_sphere_to_parallelepiped(const Eigen::Vector3d& s, const Eigen::Vector3d vertices[], double r,
                                  double& distance, Eigen::Vector3d& point_on_sphere,
                                  Eigen::Vector3d& point_on_parall)
{
  return dist_capsule_to_parallelepiped(s, s, vertices, r, distance, point_on_sphere, point_on_parall);
}

}  // namespace saras_collision
