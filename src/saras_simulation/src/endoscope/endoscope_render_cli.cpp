/**
 * @file endoscope_render_cli.cpp
 * @brief Executable endoscope_render: renders one frame of the synthetic scene with the C++ core
 *        (no ROS runtime), for tests and for timing the core (--frames N).
 *
 * Usage: endoscope_render --camera-info FILE [--width W --height H] --pose "x y z qx qy qz qw"
 *   [--boxes FILE [--boxes-pose "x y z qx qy qz qw"] [--boxes-scaling S]]
 *   [--target checkerboard|circles --target-pose "x y z roll pitch yaw"]
 *   [--shaft "tipx tipy tipz rcmx rcmy rcmz radius"]... [--uniform-texture GREY]
 *   [--out image.png] [--frames N [--moving]]
 * Poses are T_world_<frame> [m, quaternion / fixed-axis rpy rad]. With --frames N it prints the
 * renderer's set-up time (ray tables, texture) [ms], the mean wall and CPU (process, all threads)
 * time per render [ms] (static layer cached: still camera; --moving: the camera pose changes every
 * frame, as a moving ECM) and the thread CPU time of each stage of the renderer. OpenCV runs
 * single-threaded, as in endoscope_sim's eye threads.
 */
#include <chrono>
#include <ctime>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include "saras_simulation/endoscope_renderer.h"

using saras_simulation::endoscope::PlanarTarget;
using saras_simulation::endoscope::RendererOptions;
using saras_simulation::endoscope::SceneRenderer;
using saras_simulation::endoscope::Shaft;
using saras_simulation::endoscope::TissueSurface;

namespace
{
std::vector<double> numbers(const std::string& s, size_t n, const std::string& what)
{
  std::istringstream is(s);
  std::vector<double> v;
  double x;
  while (is >> x)
    v.push_back(x);
  if (v.size() != n)
    throw std::invalid_argument(what + " needs " + std::to_string(n) + " numbers");
  return v;
}

Eigen::Isometry3d poseQuat(const std::string& s, const std::string& what)
{
  const auto v = numbers(s, 7, what);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(v[6], v[3], v[4], v[5]).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

/// The command line.
struct Options
{
  std::string info, pose, boxes, boxes_pose = "0 0 0 0 0 0 1", target, target_pose = "0 0 0.085 3.14159265358979 0 0", out;
  int width = 0, height = 0, frames = 0, uniform = -1;
  double scaling = 1.0;
  bool moving = false;
  std::vector<Shaft> shafts;
};

Options parse(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i)
  {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc)
        throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--camera-info")
      o.info = next();
    else if (a == "--width")
      o.width = std::stoi(next());
    else if (a == "--height")
      o.height = std::stoi(next());
    else if (a == "--pose")
      o.pose = next();
    else if (a == "--boxes")
      o.boxes = next();
    else if (a == "--boxes-pose")
      o.boxes_pose = next();
    else if (a == "--boxes-scaling")
      o.scaling = std::stod(next());
    else if (a == "--target")
      o.target = next();
    else if (a == "--target-pose")
      o.target_pose = next();
    else if (a == "--shaft")
    {
      const auto v = numbers(next(), 7, "--shaft");
      o.shafts.push_back({ Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]), v[6] });
    }
    else if (a == "--uniform-texture")
      o.uniform = std::stoi(next());
    else if (a == "--out")
      o.out = next();
    else if (a == "--frames")
      o.frames = std::stoi(next());
    else if (a == "--moving")
      o.moving = true;
    else
      throw std::invalid_argument("unknown argument " + a);
  }
  if (o.info.empty() || o.pose.empty())
    throw std::invalid_argument("--camera-info and --pose are required");
  return o;
}

/// Bones and target of the command line into @p r.
void setScene(const Options& o, SceneRenderer& r)
{
  if (o.uniform >= 0)
    r.setUniformTexture(static_cast<unsigned char>(o.uniform));
  if (!o.boxes.empty())
  {
    const Eigen::Isometry3d Tb = poseQuat(o.boxes_pose, "--boxes-pose");
    auto bx = saras_simulation::endoscope::loadBoxes(o.boxes, o.scaling);
    for (auto& b : bx)
      for (auto& v : b)
        v = Tb * v;
    r.setBoxes(bx);
  }
  if (!o.target.empty())
  {
    const auto v = numbers(o.target_pose, 6, "--target-pose");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = saras_simulation::endoscope::rpyToMatrix(v[3], v[4], v[5]);
    T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    auto t = std::make_shared<PlanarTarget>(o.target == "checkerboard" ? PlanarTarget::checkerboard() :
                                                                           PlanarTarget::circles());
    r.setTarget(t, T);
  }
}

/// --frames N: renders N frames and prints the times.
void timeFrames(const Options& o, const Eigen::Isometry3d& T, SceneRenderer& r, cv::Mat& img)
{
  r.resetStats();
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  for (int k = 0; k < o.frames; ++k)
  {
    Eigen::Isometry3d Tk = T;
    if (o.moving)
      Tk.translation().x() += 1e-5 * (k + 1);
    r.render(Tk, o.shafts, img);
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const double cpu = 1000.0 * double(std::clock() - c0) / CLOCKS_PER_SEC;
  std::cout << "render " << r.width() << "x" << r.height() << (o.moving ? " moving" : " still") << ": "
            << ms / o.frames << " ms/frame wall, " << cpu / o.frames << " ms/frame CPU (all threads), "
            << r.backgroundRenders() << " static layers" << std::endl;
  const auto& st = r.stats();
  std::cout << "  stages [ms/frame, thread CPU]: tissue " << st.tissue_ms / o.frames << ", colour "
            << st.colour_ms / o.frames << ", boxes " << st.boxes_ms / o.frames << ", target " << st.target_ms / o.frames
            << ", copy " << st.copy_ms / o.frames << ", shafts " << st.shafts_ms / o.frames << std::endl;
}
}  // namespace

int main(int argc, char** argv)
{
  namespace es = saras_simulation::endoscope;
  try
  {
    const Options o = parse(argc, argv);
    // single-threaded OpenCV, as in endoscope_sim's eye threads (~parallel_eyes): the process CPU
    // time per frame is then the eye thread's
    cv::setNumThreads(1);
    sensor_msgs::CameraInfo info = es::readCameraInfo(o.info);
    if (o.width > 0 && o.height > 0 && (o.width != int(info.width) || o.height != int(info.height)))
      info = es::scaledCameraInfo(info, o.width, o.height);
    const auto s0 = std::chrono::steady_clock::now();
    SceneRenderer r(es::cameraModel(info), TissueSurface(), RendererOptions());
    const double setup_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - s0).count();
    setScene(o, r);
    const Eigen::Isometry3d T = poseQuat(o.pose, "--pose");
    cv::Mat img;
    r.render(T, o.shafts, img);
    if (o.frames > 0)
    {
      std::cout << "set-up " << r.width() << "x" << r.height() << ": " << setup_ms << " ms" << std::endl;
      timeFrames(o, T, r, img);
    }
    if (!o.out.empty() && !cv::imwrite(o.out, img))
      throw std::runtime_error("cannot write " + o.out);
    return 0;
  }
  catch (const std::exception& e)
  {
    std::cerr << "endoscope_render: " << e.what() << std::endl;
    return 2;
  }
}
