// Scene core tests (no ROS): per-tool minimum, nearest object, invalid tools, culling
// equivalence against a brute-force loop over the deliverable-signature functions, threshold
// zones, virtual-fixture force, and the shipped pelvis model at the simulated surgical site.
#include "saras_collision/scene.h"
#include "saras_collision/vertices_file.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <random>

using Eigen::Vector3d;
using saras_collision::CollisionScene;
using saras_collision::NearestObject;
using saras_collision::OrientedBox;
using saras_collision::ToolSpec;

namespace
{
OrientedBox aabb(const Vector3d& lo, const Vector3d& hi)
{
  OrientedBox b;
  b.center = 0.5 * (lo + hi);
  b.half = 0.5 * (hi - lo);
  b.bounding_radius = b.half.norm();
  return b;
}

std::vector<ToolSpec> fourTools()
{
  return { { "mesa_left", 0.0025 }, { "mesa_right", 0.0025 }, { "PSM1", 0.004 }, { "PSM2", 0.004 } };
}
}  // namespace

TEST(Scene, NearestToolAndBox)
{
  CollisionScene scene({ { "a", 0.01 }, { "b", 0.02 } });
  scene.setBoxes({ aabb(Vector3d(-1, -1, -1), Vector3d(1, 1, 0)) });
  // Tool a: vertical, tip 0.5 above the box top -> box at 0.49.
  ASSERT_TRUE(scene.setToolAxis(0, Vector3d(0, 0, 0.5), Vector3d(0, 0, 2)));
  // Tool b: vertical at x = 0.3, tip 0.1 above the box top -> box at 0.08; a-b axes 0.3 apart -> 0.27.
  ASSERT_TRUE(scene.setToolAxis(1, Vector3d(0.3, 0, 0.1), Vector3d(0.3, 0, 2)));
  const auto& r = scene.compute();
  EXPECT_NEAR(r[0].distance, 0.27, 1e-15);
  EXPECT_EQ(r[0].nearest.kind, NearestObject::kTool);
  EXPECT_EQ(r[0].nearest.index, 1);
  EXPECT_EQ(r[0].code, saras_collision::kParallel);
  EXPECT_NEAR((r[0].point_on_tool - r[0].point_on_object).norm(), 0.27, 1e-15);
  EXPECT_NEAR(r[0].point_on_tool.x(), 0.01, 1e-15);
  EXPECT_NEAR(r[0].point_on_object.x(), 0.28, 1e-15);
  EXPECT_TRUE(r[0].normal.isApprox(Vector3d(-1, 0, 0)));
  EXPECT_NEAR(r[1].distance, 0.08, 1e-15);
  EXPECT_EQ(r[1].nearest.kind, NearestObject::kBox);
  EXPECT_EQ(r[1].nearest.index, 0);
  EXPECT_TRUE(r[1].point_on_object.isApprox(Vector3d(0.3, 0, 0)));
  EXPECT_TRUE(r[1].point_on_tool.isApprox(Vector3d(0.3, 0, 0.08)));
  EXPECT_TRUE(r[1].normal.isApprox(Vector3d(0, 0, 1)));
}

TEST(Scene, InvalidToolsAreLeftOut)
{
  CollisionScene scene({ { "a", 0.01 }, { "b", 0.02 } });
  EXPECT_TRUE(scene.setToolAxis(0, Vector3d(0, 0, 0.5), Vector3d(0, 0, 2)));
  EXPECT_FALSE(scene.setToolAxis(1, Vector3d(std::nan(""), 0, 0.1), Vector3d(0.3, 0, 2)));
  const auto& r = scene.compute();
  EXPECT_TRUE(std::isnan(r[1].distance));
  EXPECT_EQ(r[1].code, saras_collision::kNoData);
  // Tool a has nothing to be near to.
  EXPECT_TRUE(std::isnan(r[0].distance));
  EXPECT_EQ(r[0].nearest.kind, NearestObject::kNone);
  scene.setBoxes({ aabb(Vector3d(-1, -1, -1), Vector3d(1, 1, 0)) });
  scene.compute();
  EXPECT_NEAR(r[0].distance, 0.49, 1e-15);
  scene.invalidateTool(0);
  scene.compute();
  EXPECT_TRUE(std::isnan(r[0].distance));
}

TEST(Scene, CullingNeverChangesTheResult)
{
  std::mt19937_64 gen(5);
  std::uniform_real_distribution<double> u(-0.1, 0.1), s(0.002, 0.02);
  for (int trial = 0; trial < 50; ++trial)
  {
    std::vector<OrientedBox> boxes;
    for (int b = 0; b < 100; ++b)
    {
      OrientedBox box;
      box.center = Vector3d(u(gen), u(gen), u(gen));
      box.axes = Eigen::Quaterniond(Eigen::Vector4d(u(gen), u(gen), u(gen), u(gen)).normalized()).toRotationMatrix();
      box.half = Vector3d(s(gen), s(gen), s(gen));
      box.bounding_radius = box.half.norm();
      boxes.push_back(box);
    }
    CollisionScene culled(fourTools()), brute(fourTools());
    culled.setBoxes(boxes);
    brute.setBoxes(boxes);
    brute.setCulling(false);
    std::vector<Vector3d> tips, trocars;
    for (std::size_t i = 0; i < 4; ++i)
    {
      tips.emplace_back(u(gen), u(gen), u(gen));
      trocars.emplace_back(u(gen), u(gen), 0.2);
      culled.setToolAxis(i, tips[i], trocars[i]);
      brute.setToolAxis(i, tips[i], trocars[i]);
    }
    const auto& a = culled.compute();
    const auto& b = brute.compute();
    for (std::size_t i = 0; i < 4; ++i)
    {
      ASSERT_EQ(a[i].distance, b[i].distance) << trial << " " << i;
      ASSERT_EQ(a[i].nearest.index, b[i].nearest.index);
      // Independent minimum through the deliverable-signature functions.
      double best = std::numeric_limits<double>::infinity();
      double d;
      Vector3d p, q;
      for (std::size_t j = 0; j < 4; ++j)
      {
        if (j == i)
          continue;
        saras_collision::dist_capsule_to_capsule(tips[i], trocars[i], tips[j], trocars[j], culled.tool(i).radius,
                                                 culled.tool(j).radius, d, p, q);
        best = std::min(best, d);
      }
      for (const OrientedBox& box : boxes)
      {
        Vector3d v[8];
        saras_collision::boxVertices(box, v);
        ASSERT_TRUE(saras_collision::isValidCode(
            saras_collision::dist_capsule_to_parallelepiped(tips[i], trocars[i], v, culled.tool(i).radius, d, p, q)));
        best = std::min(best, d);
      }
      ASSERT_NEAR(a[i].distance, best, 1e-12) << trial << " " << i;
    }
  }
}

TEST(Scene, ZonesAndFixtureForce)
{
  using saras_collision::Zone;
  EXPECT_EQ(saras_collision::classifyDistance(0.03, 0.005, 0.02), Zone::kSafe);
  EXPECT_EQ(saras_collision::classifyDistance(0.02, 0.005, 0.02), Zone::kWarning);
  EXPECT_EQ(saras_collision::classifyDistance(0.005, 0.005, 0.02), Zone::kCollision);
  EXPECT_EQ(saras_collision::classifyDistance(-0.01, 0.005, 0.02), Zone::kCollision);
  EXPECT_EQ(saras_collision::classifyDistance(std::nan(""), 0.005, 0.02), Zone::kUnknown);

  saras_collision::ToolProximityResult r;
  r.normal = Vector3d(0, 0, 1);
  r.distance = 0.01;
  Vector3d f = saras_collision::fixtureForce(r, 0.02, 200.0, 5.0);
  EXPECT_TRUE(f.isApprox(Vector3d(0, 0, 2.0))) << f.transpose();  // 200 N/m * 0.01 m
  r.distance = -0.05;
  f = saras_collision::fixtureForce(r, 0.02, 200.0, 5.0);
  EXPECT_TRUE(f.isApprox(Vector3d(0, 0, 5.0)));  // clamped
  r.distance = 0.02;
  EXPECT_TRUE(saras_collision::fixtureForce(r, 0.02, 200.0, 5.0).isZero());
  r.distance = std::nan("");
  EXPECT_TRUE(saras_collision::fixtureForce(r, 0.02, 200.0, 5.0).isZero());
}

// The shipped model at the simulated scene (docs/interfaces.md): bones_marker_frame at world
// (0, 0, 0.10); PSM1 trocar at world (0.10, -0.08, 0.22) = bones (0.10, -0.08, 0.12).
TEST(Scene, PelvisModelGivesWarningsAndCollisionsAtTheSite)
{
  std::vector<OrientedBox> boxes;
  std::string error;
  ASSERT_TRUE(saras_collision::loadVerticesFile(SARAS_COLLISION_CONFIG_DIR "/pelvis_vertices.txt", 1.0, 1e-6, boxes,
                                                error))
      << error;
  ASSERT_EQ(boxes.size(), 13u);
  CollisionScene scene({ { "PSM1", 0.004 } });
  scene.setBoxes(boxes);
  const Vector3d trocar(0.10, -0.08, 0.12);
  // Tip at the site centre: clear of the bones (symphysis 25 mm away).
  scene.setToolAxis(0, Vector3d(0, 0, 0), trocar);
  EXPECT_NEAR(scene.compute()[0].distance, 0.025 - 0.004, 1e-9);
  EXPECT_EQ(scene.results()[0].nearest.index, 0);  // pubic symphysis
  // 15 mm towards the feet: warning zone (6 mm).
  scene.setToolAxis(0, Vector3d(-0.015, 0, 0.01), trocar);
  EXPECT_NEAR(scene.compute()[0].distance, 0.006, 1e-9);
  EXPECT_EQ(saras_collision::classifyDistance(scene.results()[0].distance, 0.005, 0.02),
            saras_collision::Zone::kWarning);
  // 22 mm: the shaft touches the symphysis.
  scene.setToolAxis(0, Vector3d(-0.022, 0, 0.01), trocar);
  EXPECT_NEAR(scene.compute()[0].distance, -0.001, 1e-9);
  EXPECT_EQ(scene.results()[0].code, saras_collision::kIntersecting);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
