/**
 * @file endoscope_render_cli.cpp
 * @brief Executable endoscope_render: renders one frame of the synthetic scene with the C++ core
 *        (no ROS), for the comparison with the Python reference renderer
 *        (test/test_endoscope_cpp_vs_python.py) and for timing the core (--frames N).
 *
 * Usage: endoscope_render --camera-info FILE [--width W --height H] --pose "x y z qx qy qz qw"
 *   [--boxes FILE [--boxes-pose "x y z qx qy qz qw"] [--boxes-scaling S]]
 *   [--target checkerboard|circles --target-pose "x y z roll pitch yaw"]
 *   [--shaft "tipx tipy tipz rcmx rcmy rcmz radius"]... [--uniform-texture GREY]
 *   [--out image.png] [--frames N [--moving]]
 * Poses are T_world_<frame> [m, quaternion / fixed-axis rpy rad]. With --frames N it prints the
 * mean wall and CPU (process, all threads) time per render [ms] (static layer cached: still camera; --moving: the camera pose
 * changes every frame, as a moving ECM) and the thread CPU time of each stage of the renderer. OpenCV runs
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

using saras_simulation::endoscope::CameraModel;
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
}  // namespace

int main(int argc, char** argv)
{
  try
  {
    std::string info, pose, boxes, boxes_pose = "0 0 0 0 0 0 1", target, target_pose = "0 0 0.085 3.14159265358979 0 0",
                                   out;
    int width = 0, height = 0, frames = 0, uniform = -1;
    double scaling = 1.0;
    bool moving = false;
    std::vector<Shaft> shafts;
    for (int i = 1; i < argc; ++i)
    {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc)
          throw std::invalid_argument(a + " needs a value");
        return argv[++i];
      };
      if (a == "--camera-info")
        info = next();
      else if (a == "--width")
        width = std::stoi(next());
      else if (a == "--height")
        height = std::stoi(next());
      else if (a == "--pose")
        pose = next();
      else if (a == "--boxes")
        boxes = next();
      else if (a == "--boxes-pose")
        boxes_pose = next();
      else if (a == "--boxes-scaling")
        scaling = std::stod(next());
      else if (a == "--target")
        target = next();
      else if (a == "--target-pose")
        target_pose = next();
      else if (a == "--shaft")
      {
        const auto v = numbers(next(), 7, "--shaft");
        shafts.push_back({ Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]), v[6] });
      }
      else if (a == "--uniform-texture")
        uniform = std::stoi(next());
      else if (a == "--out")
        out = next();
      else if (a == "--frames")
        frames = std::stoi(next());
      else if (a == "--moving")
        moving = true;
      else
        throw std::invalid_argument("unknown argument " + a);
    }
    if (info.empty() || pose.empty())
      throw std::invalid_argument("--camera-info and --pose are required");
    // single-threaded OpenCV, as in endoscope_sim's eye threads (~parallel_eyes): the process CPU
    // time per frame is then the eye thread's
    cv::setNumThreads(1);
    CameraModel cam = CameraModel::fromYamlFile(info);
    if (width > 0 && height > 0 && (width != cam.width() || height != cam.height()))
      cam = cam.scaled(width, height);
    SceneRenderer r(cam, TissueSurface(), RendererOptions());
    if (uniform >= 0)
      r.setUniformTexture(static_cast<unsigned char>(uniform));
    if (!boxes.empty())
    {
      const Eigen::Isometry3d Tb = poseQuat(boxes_pose, "--boxes-pose");
      auto bx = saras_simulation::endoscope::loadBoxes(boxes, scaling);
      for (auto& b : bx)
        for (auto& v : b)
          v = Tb * v;
      r.setBoxes(bx);
    }
    if (!target.empty())
    {
      const auto v = numbers(target_pose, 6, "--target-pose");
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = saras_simulation::endoscope::rpyToMatrix(v[3], v[4], v[5]);
      T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
      auto t = std::make_shared<PlanarTarget>(target == "checkerboard" ? PlanarTarget::checkerboard() :
                                                                         PlanarTarget::circles());
      r.setTarget(t, T);
    }
    const Eigen::Isometry3d T = poseQuat(pose, "--pose");
    cv::Mat img;
    r.render(T, shafts, img);
    if (frames > 0)
    {
      r.resetStats();
      const auto t0 = std::chrono::steady_clock::now();
      const std::clock_t c0 = std::clock();
      for (int k = 0; k < frames; ++k)
      {
        Eigen::Isometry3d Tk = T;
        if (moving)
          Tk.translation().x() += 1e-5 * (k + 1);
        r.render(Tk, shafts, img);
      }
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      const double cpu = 1000.0 * double(std::clock() - c0) / CLOCKS_PER_SEC;
      std::cout << "render " << cam.width() << "x" << cam.height() << (moving ? " moving" : " still") << ": "
                << ms / frames << " ms/frame wall, " << cpu / frames << " ms/frame CPU (all threads), "
                << r.backgroundRenders() << " static layers" << std::endl;
      const auto& st = r.stats();
      std::cout << "  stages [ms/frame, thread CPU]: tissue " << st.tissue_ms / frames << ", colour " << st.colour_ms / frames
                << ", boxes " << st.boxes_ms / frames << ", target " << st.target_ms / frames << ", copy "
                << st.copy_ms / frames << ", shafts " << st.shafts_ms / frames << std::endl;
    }
    if (!out.empty() && !cv::imwrite(out, img))
      throw std::runtime_error("cannot write " + out);
    return 0;
  }
  catch (const std::exception& e)
  {
    std::cerr << "endoscope_render: " << e.what() << std::endl;
    return 2;
  }
}
