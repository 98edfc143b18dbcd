/**
 * @file endoscope_scene.h
 * @brief Content of the simulated surgical scene (ROS-agnostic): tissue height field, procedural
 *        tissue texture, pelvic-bone boxes, calibration targets. Units: metres, radians.
 */
#ifndef SARAS_SIMULATION_ENDOSCOPE_SCENE_H
#define SARAS_SIMULATION_ENDOSCOPE_SCENE_H

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace saras_simulation
{
namespace endoscope
{
/**
 * Height-field tissue surface in the world frame (z up):
 * z = z0 + sum_i a_i sin(kx_i (x - cx) + ky_i (y - cy) + phi_i) [m] (as tissue_surface.py).
 */
class TissueSurface
{
public:
  struct Wave
  {
    double a, kx, ky, phi;  ///< amplitude [m], wave numbers [rad/m], phase [rad]
  };
  /// The default undulations of tissue_surface.py.
  static std::vector<Wave> defaultWaves();
  /// @throws std::invalid_argument if a parameter is not finite
  explicit TissueSurface(double z0 = 0.07, double cx = 0.0, double cy = 0.0,
                         const std::vector<Wave>& waves = defaultWaves());
  /// Surface height z [m] at world (x, y) [m].
  double height(double x, double y) const;
  /// (dz/dx, dz/dy) at world (x, y).
  Eigen::Vector2d gradient(double x, double y) const;
  /// Unit outward normal at world (x, y).
  Eigen::Vector3d normal(double x, double y) const;
  double z0() const { return z0_; }
  double cx() const { return cx_; }
  double cy() const { return cy_; }

private:
  double z0_, cx_, cy_;
  std::vector<Wave> waves_;
};

/// Procedural BGR tissue texture (pink mucosa, noise blobs, vessels), deterministic for a seed.
cv::Mat tissueTexture(int size = 1024, unsigned seed = 7);

/// Oriented box: centre [m], axes (rows = unit axes), half extents [m].
struct Box
{
  Eigen::Vector3d centre;
  Eigen::Matrix3d axes;
  Eigen::Vector3d half;
  /// The 8 corners: corner b has sign +1 on axis i iff bit i of b is set.
  std::array<Eigen::Vector3d, 8> corners() const;
};

/**
 * Pelvic-bone boxes from saras_collision's forbidden-region vertices file (D7.2 Section 6.1,
 * parsed by saras_collision::loadVerticesFile: NUM, then NUM x 8 lines "x y z" in the order
 * v0, v0+x, v0+x+z, v0+z, v0+y, v0+x+y, v0+x+y+z, v0+y+z, '#' comments), times @p scaling
 * (file unit -> metres). Returns NUM arrays of the 8 vertices [m] in that order.
 * @throws std::invalid_argument with saras_collision's message ("<path>: line N: <problem>":
 *         unreadable, empty, not numeric, wrong count, not finite, not a rectangular box, trailing data)
 */
std::vector<std::array<Eigen::Vector3d, 8>> loadBoxes(const std::string& path, double scaling = 1.0);

/**
 * Oriented box of 8 vertices in the vertices-file order (saras_collision::makeBox, relative
 * tolerance saras_collision::kBoxRelativeTolerance).
 * @throws std::invalid_argument if they are not a rectangular box in that order
 */
Box boxFromVertices(const std::array<Eigen::Vector3d, 8>& v);

/**
 * A printed calibration board: grayscale texture on the board plane (z = 0 of its frame).
 * Texel (j, i) centre is at board (x_min + (i + 0.5) res, y_min + (j + 0.5) res).
 */
struct PlanarTarget
{
  std::string kind;                  ///< "checkerboard" | "circles"
  cv::Mat texture;                   ///< CV_8UC1
  double res = 1e-4;                 ///< texel size [m]
  double x_min = 0.0, y_min = 0.0;   ///< board coordinates of the texture corner [m]
  std::vector<Eigen::Vector3d> points;  ///< feature points (inner corners / dot centres), board frame [m]
  std::vector<std::array<Eigen::Vector3d, 4>> marker_corners;  ///< ArUco id i corners, board frame [m]
  double xMax() const { return x_min + texture.cols * res; }
  double yMax() const { return y_min + texture.rows * res; }

  /// cols x rows inner corners, squares of @p square [m], 1-square white margin; origin at the
  /// first inner corner, corners at (i square, j square, 0) as OpenCV object points.
  /// @throws std::invalid_argument if square is not a multiple (>= 2) of res
  static PlanarTarget checkerboard(int cols = 8, int rows = 6, double square = 0.008, double res = 0.0001);
  /// The D7.2 positioner board: @p dots black dots of @p dot_diameter on a circle of radius
  /// @p dot_circle_radius; four ArUco markers (ids 0-3) of side @p marker_side on a concentric
  /// circle of radius @p marker_circle_radius at 45, 135, 225, 315 deg. Origin at the centre [m].
  /// @throws std::invalid_argument on a bad size or unknown dictionary
  static PlanarTarget circles(double dot_circle_radius = 0.100, double dot_diameter = 0.005, int dots = 8,
                              double marker_circle_radius = 0.060, double marker_side = 0.025,
                              double res = 0.0002, const std::string& dictionary = "DICT_4X4_50");
};

/// Fixed-axis roll (x), pitch (y), yaw (z) [rad]: R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Matrix3d rpyToMatrix(double roll, double pitch, double yaw);

}  // namespace endoscope
}  // namespace saras_simulation

#endif  // SARAS_SIMULATION_ENDOSCOPE_SCENE_H
