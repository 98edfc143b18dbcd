// Benchmark of the saras_collision core (run through bench/run; not a test).
//  1. Per-query time of our exact functions, with the deliverable signatures, vs fcl::distance
//     (libfcl 0.7: its closed form for capsule-capsule and sphere-box, GJK/libccd for
//     capsule-box) on the same random queries, at FCL's default distance_tolerance (1e-6) and
//     at a tight one (1e-12, needed to agree with the exact distance within 1e-6 m).
//     Two FCL references, both with fcl::distance on the same queries:
//      - "prebuilt": FCL shapes and transforms built once outside the timed loops (FCL's
//        narrow phase alone; the strictest reference);
//      - "raw": FCL given the same raw inputs as ours (axis end-points, radii, 8 vertices or the
//        prebuilt OrientedBox), i.e. the shape objects exist already (one per role, as a user
//        keeps them) and each query sets their sizes and builds their transforms, with the
//        cheapest conversion (capsule frame: Duff et al. 2017 branchless orthonormal basis; box
//        from 8 vertices: edge lengths, unit x and y edges, z = x cross y, centre; no validation,
//        which ours does). The benchmark checks that both give the same distances.
//     Both sides read compact arrays of the same NQ (default 256) queries, hot in cache as the
//     scene's data is in the node; every loop is a direct (inlined-lambda) loop, no
//     std::function, and calls the libraries' out-of-line functions (ours in
//     libsaras_collision.so, FCL in libfcl.so: no inlining into the loop on either side); one
//     warm-up pass each, then REPS (default 41) repetitions with ours and the FCL variants
//     alternating inside every repetition (same machine load); median and minimum over the
//     repetitions.
//  2. Full colliding_regions cycle (4 tools: 6 tool pairs + 4 x N boxes) for N = 10, 100, 1000,
//     with and without bounding-sphere culling.
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/distance.h>

#include <Eigen/Geometry>

#include <chrono>
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "saras_collision/geometry.h"
#include "saras_collision/scene.h"

using Eigen::Vector3d;
using saras_collision::OrientedBox;
using Clock = std::chrono::steady_clock;

namespace
{
volatile double g_sink = 0.0;  // defeats dead-code elimination

struct Query
{
  Vector3d p1, p2, p3, p4;
  double r1, r2;
  OrientedBox box;
  Vector3d v[8];
};

/// FCL's side of one query, built once (shapes and transforms), kept apart from ours so that
/// neither side reads the other's data.
struct FclQuery
{
  fcl::Transform3d tf_cap1, tf_cap2, tf_box, tf_sphere;
  fcl::Capsuled cap1{ 0.0, 0.0 }, cap2{ 0.0, 0.0 };
  fcl::Boxd box{ 0.0, 0.0, 0.0 };
  fcl::Sphered sphere{ 0.0 };
};

std::vector<Query> makeQueries(int n, std::mt19937_64& gen, std::vector<FclQuery>& fqs)
{
  std::uniform_real_distribution<double> u(-1.0, 1.0), len(0.001, 0.12), rad(0.0, 0.01), half(0.003, 0.04);
  std::vector<Query> qs(n);
  fqs.resize(n);
  for (int k = 0; k < n; ++k)
  {
    Query& q = qs[k];
    FclQuery& f = fqs[k];
    auto segment = [&](Vector3d& a, Vector3d& b) {
      a = 0.08 * Vector3d(u(gen), u(gen), u(gen));
      b = a + Vector3d(u(gen), u(gen), u(gen)).normalized() * len(gen);
    };
    segment(q.p1, q.p2);
    segment(q.p3, q.p4);
    q.r1 = rad(gen);
    q.r2 = rad(gen);
    q.box.center = 0.02 * Vector3d(u(gen), u(gen), u(gen));
    q.box.axes = Eigen::Quaterniond(Eigen::Vector4d(u(gen), u(gen), u(gen), u(gen)).normalized()).toRotationMatrix();
    q.box.half = Vector3d(half(gen), half(gen), half(gen));
    q.box.bounding_radius = q.box.half.norm();
    saras_collision::boxVertices(q.box, q.v);
    auto capsuleTf = [](const Vector3d& a, const Vector3d& b) {
      fcl::Transform3d tf = fcl::Transform3d::Identity();
      tf.translation() = 0.5 * (a + b);
      tf.linear() = Eigen::Quaterniond::FromTwoVectors(Vector3d::UnitZ(), b - a).toRotationMatrix();
      return tf;
    };
    f.tf_cap1 = capsuleTf(q.p1, q.p2);
    f.tf_cap2 = capsuleTf(q.p3, q.p4);
    f.tf_box = fcl::Transform3d::Identity();
    f.tf_box.translation() = q.box.center;
    f.tf_box.linear() = q.box.axes;
    f.tf_sphere = fcl::Transform3d::Identity();
    f.tf_sphere.translation() = q.p1;
    f.cap1 = fcl::Capsuled(q.r1, (q.p2 - q.p1).norm());
    f.cap2 = fcl::Capsuled(q.r2, (q.p4 - q.p3).norm());
    f.box = fcl::Boxd(2 * q.box.half);
    f.sphere = fcl::Sphered(q.r1);
  }
  return qs;
}

/// Time of one pass of @p pass over @p n queries, per query [ns].
template <typename F>
double nsPerPass(int n, F&& pass)
{
  const auto t0 = Clock::now();
  pass();
  return std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / n;
}

/// Best of @p reps runs (the machine is shared).
template <typename F>
double bestNs(int reps, int calls, F&& f)
{
  double best = 1e300;
  for (int r = 0; r < reps; ++r)
  {
    const auto t0 = Clock::now();
    for (int i = 0; i < calls; ++i)
      f(i);
    best = std::min(best, std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / calls);
  }
  return best;
}

/// Capsule [a, b] as FCL wants it: a proper rotation whose z axis is along b - a (Duff et al.,
/// "Building an orthonormal basis, revisited", JCGT 2017: branchless), centred at the midpoint.
inline void capsuleTransform(const Vector3d& a, const Vector3d& b, fcl::Transform3d& tf, double& length)
{
  const Vector3d d = b - a;
  length = d.norm();
  const Vector3d z = d * (1.0 / length);
  const double sign = std::copysign(1.0, z.z());
  const double k = -1.0 / (sign + z.z());
  const double m = z.x() * z.y() * k;
  auto& r = tf.matrix();
  r(0, 0) = 1.0 + sign * z.x() * z.x() * k;
  r(1, 0) = sign * m;
  r(2, 0) = -sign * z.x();
  r(0, 1) = m;
  r(1, 1) = sign + z.y() * z.y() * k;
  r(2, 1) = -z.y();
  r(0, 2) = z.x();
  r(1, 2) = z.y();
  r(2, 2) = z.z();
  tf.translation() = 0.5 * (a + b);
}

/// Box from its 8 vertices (documented order) as FCL wants it: sides, proper rotation, centre.
inline void boxFromVertices(const Vector3d v[], fcl::Boxd& box, fcl::Transform3d& tf)
{
  const Vector3d ex = v[1] - v[0], ey = v[4] - v[0], ez = v[3] - v[0];
  const double lx = ex.norm(), ly = ey.norm(), lz = ez.norm();
  const Vector3d x = ex * (1.0 / lx), y = ey * (1.0 / ly);
  tf.linear().col(0) = x;
  tf.linear().col(1) = y;
  tf.linear().col(2) = x.cross(y);
  tf.translation() = 0.5 * (v[0] + v[6]);
  box.side = Vector3d(lx, ly, lz);
}
/// FCL's shape objects and transforms of a caller that converts raw inputs per query.
struct FclRawShapes
{
  fcl::Capsuled cap1{ 0.0, 0.0 }, cap2{ 0.0, 0.0 };
  fcl::Sphered sphere{ 0.0 };
  fcl::Boxd box{ 0.0, 0.0, 0.0 };
  fcl::Transform3d tf1 = fcl::Transform3d::Identity(), tf2 = fcl::Transform3d::Identity();
};

/// One FCL query from the raw inputs of ours (kind: 0 capsule-capsule, 1 capsule-box 8
/// vertices, 2 sphere-box 8 vertices, 3 capsule-box prebuilt box, 4 sphere-box prebuilt box;
/// the box transform of kinds 3 and 4 is copied from the prebuilt OrientedBox), with the shape
/// objects and transforms of the caller. @return the distance
double fclRawQuery(const Query& q, int kind, FclRawShapes& sh, const fcl::DistanceRequestd& req)
{
  fcl::DistanceResultd res;
  if (kind == 0 || kind == 1 || kind == 3)
  {
    capsuleTransform(q.p1, q.p2, sh.tf1, sh.cap1.lz);
    sh.cap1.radius = q.r1;
  }
  else
  {
    sh.tf1.translation() = q.p1;
    sh.sphere.radius = q.r1;
  }
  if (kind == 0)
  {
    capsuleTransform(q.p3, q.p4, sh.tf2, sh.cap2.lz);
    sh.cap2.radius = q.r2;
    fcl::distance(&sh.cap1, sh.tf1, &sh.cap2, sh.tf2, req, res);
    return res.min_distance;
  }
  if (kind <= 2)
  {
    boxFromVertices(q.v, sh.box, sh.tf2);
  }
  else
  {
    sh.tf2.linear() = q.box.axes;
    sh.tf2.translation() = q.box.center;
    sh.box.side = 2.0 * q.box.half;
  }
  if (kind == 1 || kind == 3)
    fcl::distance(&sh.cap1, sh.tf1, &sh.box, sh.tf2, req, res);
  else
    fcl::distance(&sh.sphere, sh.tf1, &sh.box, sh.tf2, req, res);
  return res.min_distance;
}

/// fcl::distance on the prebuilt shapes of @p f (kind: 0 capsule-capsule, 1 capsule-box,
/// 2 sphere-box). @return the distance
double fclPrebuiltQuery(const FclQuery& f, int kind, const fcl::DistanceRequestd& req)
{
  fcl::DistanceResultd res;
  if (kind == 0)
    fcl::distance(&f.cap1, f.tf_cap1, &f.cap2, f.tf_cap2, req, res);
  else if (kind == 1)
    fcl::distance(&f.cap1, f.tf_cap1, &f.box, f.tf_box, req, res);
  else
    fcl::distance(&f.sphere, f.tf_sphere, &f.box, f.tf_box, req, res);
  return res.min_distance;
}

/// Largest |FCL raw - FCL prebuilt| distance over the queries of a row (the conversion check).
double rawMismatch(const std::vector<Query>& qs, const std::vector<FclQuery>& fqs, int kind, int raw_kind)
{
  fcl::DistanceRequestd req;
  req.enable_nearest_points = true;
  FclRawShapes shapes;
  double worst = 0.0;
  for (std::size_t i = 0; i < qs.size(); ++i)
    worst = std::max(worst, std::abs(fclRawQuery(qs[i], raw_kind, shapes, req) - fclPrebuiltQuery(fqs[i], kind, req)));
  return worst;
}

/// Median and minimum of @p t (sorted in place).
void medianMin(std::vector<double>& t, double& med, double& lo)
{
  std::sort(t.begin(), t.end());
  med = t[t.size() / 2];
  lo = t.front();
}

/**
 * Full colliding_regions cycle (4 tools: 6 capsule pairs + 4 x N capsule-box) for N = 10, 100,
 * 1000 random boxes, with and without bounding-sphere culling: best of @p reps runs [us].
 */
void fullCycleTable(int reps, std::mt19937_64& gen)
{
  std::printf("# full cycle: 4 tools (6 capsule pairs + 4 x N capsule-box), best of %d runs\n", reps);
  std::printf("%-8s %16s %18s\n", "N boxes", "culling [us]", "no culling [us]");
  for (int nb : { 10, 100, 1000 })
  {
    std::uniform_real_distribution<double> u(-0.1, 0.1), s(0.003, 0.02);
    std::vector<OrientedBox> boxes(nb);
    for (OrientedBox& box : boxes)
    {
      box.center = Vector3d(u(gen), u(gen), 0.5 * u(gen) - 0.05);
      box.axes = Eigen::Quaterniond(Eigen::Vector4d(u(gen), u(gen), u(gen), u(gen)).normalized()).toRotationMatrix();
      box.half = Vector3d(s(gen), s(gen), s(gen));
      box.bounding_radius = box.half.norm();
    }
    saras_collision::CollisionScene scene(
        { { "mesa_left", 0.0025 }, { "mesa_right", 0.0025 }, { "PSM1", 0.004 }, { "PSM2", 0.004 } });
    scene.setBoxes(boxes);
    const Vector3d trocars[4] = { Vector3d(0.02, 0.13, 0.10), Vector3d(0.02, -0.13, 0.10),
                                  Vector3d(0.10, -0.08, 0.12), Vector3d(0.10, 0.08, 0.12) };
    const int cycles = nb >= 1000 ? 200 : 2000;
    std::vector<Vector3d> tips(cycles * 4);
    for (Vector3d& t : tips)
      t = Vector3d(0.4 * u(gen), 0.4 * u(gen), 0.2 * u(gen));
    auto run = [&](bool culling) {
      scene.setCulling(culling);
      return bestNs(reps, cycles,
                    [&](int c) {
                      for (int i = 0; i < 4; ++i)
                        scene.setToolAxis(i, tips[4 * c + i], trocars[i]);
                      g_sink = g_sink + scene.compute()[0].distance;
                    }) /
             1000.0;
    };
    const double with = run(true), without = run(false);
    std::printf("%-8d %16.2f %18.2f\n", nb, with, without);
  }
}
/// The per-query table: ours vs the FCL references on the same queries.
struct QueryTable
{
  const std::vector<Query>& qs;
  const std::vector<FclQuery>& fqs;
  int reps;
  double max_raw_mismatch = 0.0;

  /// One pass of FCL on the prebuilt shapes at distance tolerance @p tol.
  void fclPass(double tol, int kind) const
  {
    fcl::DistanceRequestd req;
    req.distance_tolerance = tol;
    req.enable_nearest_points = true;  // ours returns the points too
    for (const FclQuery& f : fqs)
      g_sink = g_sink + fclPrebuiltQuery(f, kind, req);
  }

  /// One pass of FCL from the raw inputs of ours.
  void fclRawPass(int raw_kind) const
  {
    fcl::DistanceRequestd req;
    req.enable_nearest_points = true;
    FclRawShapes shapes;
    for (const Query& q : qs)
      g_sink = g_sink + fclRawQuery(q, raw_kind, shapes, req);
  }

  /// Times @p ours and the three FCL references, alternating inside every repetition; prints a row.
  template <typename F>
  void row(const char* name, F&& ours, int kind, int raw_kind)
  {
    const int n = static_cast<int>(qs.size());
    auto f6 = [&] { fclPass(1e-6, kind); };
    auto f12 = [&] { fclPass(1e-12, kind); };
    auto fraw = [&] { fclRawPass(raw_kind); };
    ours();  // warm-up (caches, branch predictors, page faults)
    f6();
    f12();
    fraw();
    // FCL from raw inputs must compute the same distances as FCL on the prebuilt transforms.
    max_raw_mismatch = std::max(max_raw_mismatch, rawMismatch(qs, fqs, kind, raw_kind));
    std::vector<double> t[4];
    for (int r = 0; r < reps; ++r)
    {
      t[0].push_back(nsPerPass(n, ours));
      t[1].push_back(nsPerPass(n, f6));
      t[2].push_back(nsPerPass(n, f12));
      t[3].push_back(nsPerPass(n, fraw));
    }
    double med[4], lo[4];
    char c[4][40];
    for (int i = 0; i < 4; ++i)
    {
      medianMin(t[i], med[i], lo[i]);
      std::snprintf(c[i], sizeof(c[i]), "%.1f [%.1f]", med[i], lo[i]);
    }
    std::printf("%-18s %15s %17s %17s %17s %7.1fx %7.1fx %7.1fx\n", name, c[0], c[1], c[2], c[3], med[1] / med[0],
                med[2] / med[0], med[3] / med[0]);
  }
};

/// Per-query time of our exact functions vs fcl::distance (see the file comment).
void queryTable(const std::vector<Query>& qs, const std::vector<FclQuery>& fqs, int reps)
{
  std::printf("# saras_collision benchmark: %d random queries (same for both), %d repetitions, ns per query\n",
              static_cast<int>(qs.size()), reps);
  std::printf("# median [minimum] over the repetitions; ratio = FCL / ours (medians)\n");
  std::printf("# FCL prebuilt: shapes and transforms built before the timed loop (narrow phase only), at\n"
              "#   distance_tolerance 1e-6 (default) and 1e-12; FCL raw: from the same raw inputs as ours\n"
              "#   (sizes and transforms set per query), tolerance 1e-6\n");
  std::printf("%-18s %15s %17s %17s %17s %8s %8s %8s\n", "query", "ours [ns]", "FCL prebuilt 1e-6",
              "FCL prebuilt 1e-12", "FCL raw 1e-6", "ratio", "ratio", "ratio");
  std::printf("%-18s %15s %17s %17s %17s %8s %8s %8s\n", "", "", "[ns]", "[ns]", "[ns]", "1e-6", "1e-12", "raw");
  double d;
  Vector3d a, b;
  QueryTable table{ qs, fqs, reps };
  table.row("capsule-capsule", [&] {
    for (const Query& q : qs)
    {
      saras_collision::dist_capsule_to_capsule(q.p1, q.p2, q.p3, q.p4, q.r1, q.r2, d, a, b);
      g_sink = g_sink + d;
    }
  }, 0, 0);
  table.row("capsule-box (8 v)", [&] {
    for (const Query& q : qs)
    {
      saras_collision::dist_capsule_to_parallelepiped(q.p1, q.p2, q.v, q.r1, d, a, b);
      g_sink = g_sink + d;
    }
  }, 1, 1);
  table.row("sphere-box (8 v)", [&] {
    for (const Query& q : qs)
    {
      saras_collision::dist_sphere_to_parallelepiped(q.p1, q.v, q.r1, d, a, b);
      g_sink = g_sink + d;
    }
  }, 2, 2);
  table.row("capsule-box (box)", [&] {
    for (const Query& q : qs)
      g_sink = g_sink + saras_collision::capsuleBox(q.p1, q.p2, q.r1, q.box).distance;
  }, 1, 3);
  table.row("sphere-box (box)", [&] {
    for (const Query& q : qs)
      g_sink = g_sink + saras_collision::capsuleBox(q.p1, q.p1, q.r1, q.box).distance;
  }, 2, 4);
  std::printf("(8 v: deliverable signatures, box validated from its 8 vertices on every call; box: prebuilt\n"
              " OrientedBox, capsuleBox(), as the node uses)\n");
  std::printf("check: max |FCL raw - FCL prebuilt| distance over every row's queries = %.1e m\n\n",
              table.max_raw_mismatch);
}
}  // namespace

int main()
{
  std::mt19937_64 gen(42);
  const char* nq = std::getenv("NQ");
  const char* nr = std::getenv("REPS");
  const int n = nq != nullptr ? std::max(1, std::atoi(nq)) : 256;
  const int reps = nr != nullptr ? std::max(1, std::atoi(nr)) : 41;
  std::vector<FclQuery> fqs;
  const std::vector<Query> qs = makeQueries(n, gen, fqs);
  queryTable(qs, fqs, reps);
  fullCycleTable(reps, gen);
  return 0;
}
