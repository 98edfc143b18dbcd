// Exact capsule-box and sphere-box distances and the box validation (capsule-capsule:
// capsule_capsule.cpp). See include/saras_collision/geometry.h for the definitions and the
// return codes; the derivations are summarised next to each function.
#include "saras_collision/geometry.h"

#include "geometry_detail.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

namespace saras_collision
{
using namespace detail;  // NOLINT(build/namespaces): this library's own private helpers

namespace
{
/// The 8 vertices all finite (pairwise sum, see allFinite).
inline bool verticesFinite(const Eigen::Vector3d v[])
{
  const Eigen::Vector3d s = ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7]));
  return std::isfinite(s.sum());
}


/// Edge vectors of 8 box vertices (documented order) and their squared lengths.
struct BoxEdges
{
  Eigen::Vector3d ex, ey, ez;  ///< v1 - v0, v4 - v0, v3 - v0 [m]
  double lx2, ly2, lz2;  ///< squared edge lengths [m^2]
};

/// Edge vectors and squared lengths of 8 vertices (documented order), first part of the box test.
void boxEdges(const Eigen::Vector3d v[], BoxEdges& e)
{
  const Eigen::Vector3d& v0 = v[0];
  e.ex = v[1] - v0;
  e.ey = v[4] - v0;
  e.ez = v[3] - v0;
  e.lx2 = e.ex.squaredNorm();
  e.ly2 = e.ey.squaredNorm();
  e.lz2 = e.ez.squaredNorm();
}

/// The combined shape test of validateBox() on edges from boxEdges(): true for a box within rt.
bool boxShapePasses(const Eigen::Vector3d v[], const BoxEdges& e, double rt2)
{
  const double diag2 = e.lx2 + e.ly2 + e.lz2;
  const double tol2 = rt2 * diag2;
  const double xy = e.ex.dot(e.ey), xz = e.ex.dot(e.ez), yz = e.ey.dot(e.ez);
  const double cos2 = (xy * xy) * e.lz2 + (xz * xz) * e.ly2 + (yz * yz) * e.lx2;
  const Eigen::Array3d r2 = ((v[2] - v[3]) - e.ex).array(), r5 = ((v[5] - v[4]) - e.ex).array();
  const Eigen::Array3d r6 = ((v[6] - v[5]) - e.ez).array(), r7 = ((v[7] - v[4]) - e.ez).array();
  const double residual2 = ((r2 * r2 + r5 * r5) + (r6 * r6 + r7 * r7)).sum();
  return diag2 < std::numeric_limits<double>::infinity() && std::min({ e.lx2, e.ly2, e.lz2 }) > tol2 &&
         cos2 <= rt2 * (e.lx2 * e.ly2 * e.lz2) && residual2 <= tol2;
}

/**
 * Checks that 8 vertices are a rectangular box in the documented order, within the relative
 * tolerance rt (@p rt2 = rt^2):
 *  - edges finite and not flat: min_i |e_i|^2 > rt^2 |diag|^2, |diag|^2 = sum_i |e_i|^2;
 *  - rectangular: sum over the 3 edge pairs of cos^2 <= rt^2, tested without division as
 *    sum (e_i.e_j)^2 |e_k|^2 <= rt^2 |e_x|^2 |e_y|^2 |e_z|^2;
 *  - order: the 4 residuals v2 - v3 - e_x, v5 - v4 - e_x, v6 - v5 - e_z, v7 - v4 - e_z (zero
 *    for a box: each is one parallel edge minus another) have a sum of squared norms
 *    <= rt^2 |diag|^2. Every vertex enters one of them.
 * Each test is written to be false on NaN, so non-finite vertices fail them (an infinite edge
 * fails the first test, then every residual with a non-finite vertex is NaN or infinite); only
 * then are the vertices scanned to tell kInvalidInput from kInvalidBox.
 * @return kSeparated (valid), kInvalidBox or kInvalidInput
 */
int validateBox(const Eigen::Vector3d v[], double rt2, BoxEdges& e)
{
  boxEdges(v, e);
  if (boxShapePasses(v, e, rt2))
    return kSeparated;
  return verticesFinite(v) ? kInvalidBox : kInvalidInput;
}

/// Fills centre, axes and half extents of @p box from validated vertices (not the bounding
/// radius). Gram-Schmidt keeps x exact; the residual non-orthogonality is within the
/// tolerance. The handedness of the vertex order is kept.
void boxFrame(const Eigen::Vector3d v[], const BoxEdges& e, OrientedBox& box)
{
  const double lx = std::sqrt(e.lx2), ly = std::sqrt(e.ly2), lz = std::sqrt(e.lz2);
  const Eigen::Vector3d x = e.ex * (1.0 / lx);
  Eigen::Vector3d y = e.ey - e.ey.dot(x) * x;
  y *= 1.0 / y.norm();
  const Eigen::Vector3d z = x.cross(y);
  box.center = 0.5 * (v[0] + v[6]);  // midpoint of the main diagonal
  box.axes.col(0) = x;
  box.axes.col(1) = y;
  box.axes.col(2) = z.dot(e.ez) < 0.0 ? Eigen::Vector3d(-z) : z;
  box.half = Eigen::Vector3d(lx, ly, lz) * 0.5;
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
  if (!verticesFinite(vertices))
    return kInvalidInput;
  if (!(relative_tolerance >= 0.0) || !std::isfinite(relative_tolerance))
    return kInvalidInput;
  BoxEdges e;
  const int code = validateBox(vertices, relative_tolerance * relative_tolerance, e);
  if (code != kSeparated)
    return code;
  boxFrame(vertices, e, box);
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
namespace
{
/// The result for the closest axis point @p axis_point (world) outside the box: @p v = that point
/// minus the closest box point, in box coordinates, |v| = @p axis > 0.
DistanceResult outsideResult(const Eigen::Vector3d& axis_point, const Eigen::Vector3d& v, double axis, double r,
                             const OrientedBox& box)
{
  DistanceResult out;
  out.distance = axis - r;
  out.code = classify(out.distance);
  const Eigen::Vector3d v_world = box.axes * v;  // axis point - box point, world
  out.normal = v_world / axis;
  out.point2 = axis_point - v_world;
  out.point1 = axis_point - (surfaceFactor(out.distance) * r) * out.normal;
  return out;
}

/// x clamped to the box [-h, h] (box coordinates).
Eigen::Vector3d clampToBox(const Eigen::Vector3d& x, const Eigen::Vector3d& h)
{
  return Eigen::Vector3d(clampTo(x[0], h[0]), clampTo(x[1], h[1]), clampTo(x[2], h[2]));
}

/**
 * The minimiser t in [0, 1] of F(t) (see above) for the axis x(t) = a + t d in box coordinates:
 * the zero of F'(t), found by walking its (at most 6) sorted breakpoints and interpolating
 * linearly inside the piece where F' changes sign.
 */
double closestAxisParameter(const Eigen::Vector3d& a, const Eigen::Vector3d& d, const Eigen::Vector3d& h)
{
  auto slope = [&](double t) {
    double g = 0.0;
    for (int i = 0; i < 3; ++i)
    {
      const double x = a[i] + t * d[i];
      g += d[i] * (x - clampTo(x, h[i]));
    }
    return g;
  };
  const double g0 = d.isZero(0.0) ? 0.0 : slope(0.0);  // sphere: t = 0
  if (!(g0 < 0.0))
    return 0.0;
  const double g1 = slope(1.0);
  if (g1 <= 0.0)
    return 1.0;
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
  for (int k = 0; k < n; ++k)
  {
    const double g = k + 1 == n ? g1 : slope(bp[k]);
    if (g >= 0.0)
    {
      const double t = t_prev + (-g_prev) * (bp[k] - t_prev) / (g - g_prev);
      return std::min(std::max(t, t_prev), bp[k]);
    }
    t_prev = bp[k];
    g_prev = g;
  }
  return 1.0;
}

/**
 * The axis reaches the box: the deepest axis point (minimum of G from minimumDepth(), @p t_hint
 * an extra candidate) and, when intersecting, its projection on the nearest face.
 */
DistanceResult reachingResult(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r,
                              const OrientedBox& box, const Eigen::Vector3d& a, const Eigen::Vector3d& d,
                              double t_hint)
{
  const Eigen::Vector3d& h = box.half;
  double best_t = t_hint;
  const double best = minimumDepth(a, d, h, t_hint, &best_t);
  const Eigen::Vector3d x = a + best_t * d;
  const Eigen::Vector3d axis_point = p1 + best_t * (p2 - p1);
  DistanceResult out;
  out.distance = std::min(best, 0.0) - r;
  out.code = classify(out.distance);
  int face = 0;
  (x.cwiseAbs() - h).maxCoeff(&face);  // nearest face: largest |x_i| - h_i
  const double sign = x[face] < 0.0 ? -1.0 : 1.0;
  out.normal = box.axes.col(face) * sign;
  out.point1 = axis_point;
  if (out.code == kIntersecting)
  {
    Eigen::Vector3d on_face = x;
    on_face[face] = sign * h[face];
    out.point2 = box.center + box.axes * on_face;
  }
  else
  {
    out.point2 = axis_point;  // tangent: zero radius axis touching the box
  }
  return out;
}

/// capsuleBox() without the input checks (inputs finite, r >= 0).
DistanceResult capsuleBoxChecked(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r,
                                 const OrientedBox& box)
{
  const Eigen::Matrix3d& R = box.axes;
  const Eigen::Vector3d& h = box.half;
  const Eigen::Vector3d a = R.transpose() * (p1 - box.center);
  if (p1 == p2)
  {
    // Sphere with its centre outside the box: closest box point = clamped centre (inside: the
    // general path, whose depth walk reduces to the nearest face for d = 0).
    const Eigen::Vector3d v = a - clampToBox(a, h);
    const double axis2 = v.squaredNorm();
    if (axis2 > 0.0)
      return outsideResult(p1, v, std::sqrt(axis2), r, box);
  }
  const Eigen::Vector3d d = R.transpose() * (p2 - p1);  // exactly zero for a sphere
  const double t = closestAxisParameter(a, d, h);
  const Eigen::Vector3d x = a + t * d;
  const Eigen::Vector3d v = x - clampToBox(x, h);
  const double axis = v.norm();
  // Entering the box leaves x(t*) on its boundary up to rounding: below the tangent tolerance
  // the depth computation decides (it returns >= 0 only if the axis merely touches).
  if (axis > kTangentTolerance || (axis > 0.0 && minimumDepth(a, d, h, t) >= 0.0))
    return outsideResult(p1 + t * (p2 - p1), v, axis, r, box);
  return reachingResult(p1, p2, r, box, a, d, t);
}

}  // namespace

DistanceResult capsuleBox(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2, double r, const OrientedBox& box)
{
  if (!allFinite(p1, p2) || !validRadius(r))
    return invalid(kInvalidInput);
  return capsuleBoxChecked(p1, p2, r, box);
}


// The box is validated and its frame built on every call; the query is
// then capsuleBox(). Prebuild an OrientedBox with makeBox() for repeated queries.
int dist_capsule_to_parallelepiped(const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                                   const Eigen::Vector3d vertices[], double r, double& distance,
                                   Eigen::Vector3d& point_on_capsule, Eigen::Vector3d& point_on_parall)
{
  if (vertices == nullptr || !allFinite(p1, p2) || !validRadius(r))
    return invalidOutputs(kInvalidInput, distance, point_on_capsule, point_on_parall);
  BoxEdges e;
  const int valid = validateBox(vertices, kBoxRelativeTolerance * kBoxRelativeTolerance, e);
  if (valid != kSeparated)
    return invalidOutputs(valid, distance, point_on_capsule, point_on_parall);
  OrientedBox box;
  boxFrame(vertices, e, box);
  const DistanceResult res = capsuleBoxChecked(p1, p2, r, box);
  distance = res.distance;
  point_on_capsule = res.point1;
  point_on_parall = res.point2;
  return res.code;
}

// Sphere-box directly in the (validated) vertex frame, without building an orthonormal frame:
// with e_i the edge vectors from v0 and u_i = (s - v0).e_i, the centre's coordinates along the
// edges are u_i / |e_i|^2 in [0, 1] inside the box; the closest box point clamps u_i to
// [0, |e_i|^2] (Ericson 5.1.4), and s minus it is sum_i (u_i - clamp(u_i)) / |e_i|^2 e_i.
// Only a centre inside the box needs the edge lengths (depth to the nearest face).
int dist_sphere_to_parallelepiped(const Eigen::Vector3d& s, const Eigen::Vector3d vertices[], double r,
                                  double& distance, Eigen::Vector3d& point_on_sphere,
                                  Eigen::Vector3d& point_on_parall)
{
  if (vertices == nullptr || !std::isfinite(s.sum() + r) || !(r >= 0.0))
    return invalidOutputs(kInvalidInput, distance, point_on_sphere, point_on_parall);
  BoxEdges e;
  const int valid = validateBox(vertices, kBoxRelativeTolerance * kBoxRelativeTolerance, e);
  if (valid != kSeparated)
    return invalidOutputs(valid, distance, point_on_sphere, point_on_parall);
  const Eigen::Vector3d w = s - vertices[0];
  const double ux = w.dot(e.ex), uy = w.dot(e.ey), uz = w.dot(e.ez);
  const double cx = std::min(std::max(ux, 0.0), e.lx2);
  const double cy = std::min(std::max(uy, 0.0), e.ly2);
  const double cz = std::min(std::max(uz, 0.0), e.lz2);
  // Centre minus closest box point, world [m].
  const double ix = 1.0 / e.lx2, iy = 1.0 / e.ly2, iz = 1.0 / e.lz2;
  const Eigen::Vector3d off = ((ux - cx) * ix) * e.ex + ((uy - cy) * iy) * e.ey + ((uz - cz) * iz) * e.ez;
  const double axis2 = off.squaredNorm();
  // Squared distance overflowed (centre beyond ~1e154 m from the box): not a number to use.
  if (!(axis2 < std::numeric_limits<double>::infinity()))
    return invalidOutputs(kInvalidInput, distance, point_on_sphere, point_on_parall);
  if (axis2 > kMinAxis2)  // centre outside the box (by more than 1e-100 m)
  {
    const double axis = std::sqrt(axis2);
    const double dist = axis - r;
    const double scale = surfaceFactor(dist) * r / axis;
    distance = dist;
    point_on_parall = s - off;
    point_on_sphere = s - scale * off;
    return classify(dist);
  }
  // Centre inside (or on the surface): depth to the nearest face, min_i min(u_i, l_i^2 - u_i) / l_i.
  const double l2[3] = { e.lx2, e.ly2, e.lz2 };
  const double u[3] = { ux, uy, uz };
  const Eigen::Vector3d* edge[3] = { &e.ex, &e.ey, &e.ez };
  int face = 0;
  double depth = std::numeric_limits<double>::infinity(), sign = 1.0, length = 1.0;
  for (int i = 0; i < 3; ++i)
  {
    const double l = std::sqrt(l2[i]);
    const double high = l2[i] - u[i];  // towards the face at v0 + e_i
    const double di = std::min(u[i], high) / l;
    if (di < depth)
    {
      depth = di;
      face = i;
      sign = high <= u[i] ? 1.0 : -1.0;
      length = l;
    }
  }
  distance = -depth - r;
  const Eigen::Vector3d normal = *edge[face] * (sign / length);
  point_on_sphere = s;
  point_on_parall = s + ((1.0 - surfaceFactor(distance)) * depth) * normal;  // tangent: s
  return classify(distance);
}

}  // namespace saras_collision
