/**
 * @file stereo_contact_eval.cpp
 * @brief Executable stereo_contact_eval (no ROS): runs StereoContactEstimator on one stereo pair of
 *        PNG files and prints one JSON line (state, depth, normal, confidence, thread CPU per call).
 *        Driven by bench/contact_accuracy.
 *
 * Usage: stereo_contact_eval LEFT.png RIGHT.png --camera "w h fx fy cx cy k1 k2 p1 p2 k3"
 *          --baseline B --tool "tx ty tz sx sy sz radius" [--tool ...] [--repeat N]
 *          [--patch M] [--max-roi PX] [--refine N]   (StereoContactParams, defaults otherwise)
 * Parallel optical frames (R = I), right eye at +B along x. Tools in the left optical frame [m]:
 * tip, a point up the shaft, radius; the first tool is estimated, all are masked.
 */
#include <cstdio>
#include <ctime>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include "saras_visual_feedback/stereo_contact.h"

using namespace saras_visual_feedback;  // NOLINT(build/namespaces) executable

namespace
{
std::vector<double> numbers(const std::string& s, std::size_t n, const std::string& what)
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

double threadCpuMs()
{
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

StereoCalibration calibration(const std::vector<double>& c, double baseline)
{
  CameraIntrinsics k;
  k.width = static_cast<int>(c[0]);
  k.height = static_cast<int>(c[1]);
  k.fx = c[2];
  k.fy = c[3];
  k.cx = c[4];
  k.cy = c[5];
  k.model = DistortionModel::kPlumbBob;
  k.d = {c[6], c[7], c[8], c[9], c[10], 0, 0, 0};
  StereoCalibration cal;
  cal.left = cal.right = k;
  cal.P_left = cv::Matx34d(k.fx, 0, k.cx, 0, 0, k.fy, k.cy, 0, 0, 0, 1, 0);
  cal.P_right = cal.P_left;
  cal.P_right(0, 3) = -k.fx * baseline;
  return cal;
}
}  // namespace

int main(int argc, char** argv)
{
  try
  {
    std::vector<std::string> files;
    std::string camera;
    double baseline = 0.005;
    int repeat = 1;
    StereoContactParams params;
    std::vector<InstrumentView> tools;
    for (int i = 1; i < argc; ++i)
    {
      const std::string a = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc)
          throw std::invalid_argument(a + " needs a value");
        return argv[++i];
      };
      if (a == "--camera")
        camera = next();
      else if (a == "--baseline")
        baseline = std::stod(next());
      else if (a == "--patch")
        params.patch_radius = std::stod(next());
      else if (a == "--max-roi")
        params.max_roi = std::stoi(next());
      else if (a == "--grid")
        params.sample_grid = std::stoi(next());
      else if (a == "--refine")
        params.refine_iterations = std::stoi(next());
      else if (a == "--repeat")
        repeat = std::max(1, std::stoi(next()));
      else if (a == "--tool")
      {
        const auto v = numbers(next(), 7, "--tool");
        InstrumentView t;
        t.valid = true;
        t.tip = cv::Point3d(v[0], v[1], v[2]);
        t.has_shaft = true;
        t.shaft = cv::Point3d(v[3], v[4], v[5]);
        t.radius = v[6];
        tools.push_back(t);
      }
      else
        files.push_back(a);
    }
    if (files.size() != 2 || camera.empty() || tools.empty())
      throw std::invalid_argument("usage: stereo_contact_eval LEFT RIGHT --camera \"w h fx fy cx cy k1 k2 p1 p2 k3\" "
                                  "--baseline B --tool \"tx ty tz sx sy sz r\" [--repeat N]");
    cv::setNumThreads(1);  // the CPU figure is one thread's
    const cv::Mat left = cv::imread(files[0], cv::IMREAD_COLOR), right = cv::imread(files[1], cv::IMREAD_COLOR);
    if (left.empty() || right.empty())
      throw std::invalid_argument("cannot read the images");
    std::string why;
    if (!validateStereoContactParams(params, &why))
      throw std::invalid_argument(why);
    StereoContactEstimator e(params);
    if (!e.configure(calibration(numbers(camera, 11, "--camera"), baseline), &why))
      throw std::invalid_argument(why);
    ContactEstimate c = e.estimate(left, right, tools.data(), tools.size(), 0);  // warm-up (allocations)
    const double t0 = threadCpuMs();
    for (int k = 0; k < repeat; ++k)
      c = e.estimate(left, right, tools.data(), tools.size(), 0);
    const double cpu = (threadCpuMs() - t0) / repeat;
    std::printf("{\"state\": \"%s\", \"unknown\": \"%s\", \"depth\": %.6f, \"signed_distance\": %.6f, "
                "\"normal\": [%.6f, %.6f, %.6f], \"confidence\": %.3f, \"points\": %d, \"cpu_ms\": %.3f}\n",
                toString(c.state), toString(c.unknown), c.depth, c.signed_distance, c.normal[0], c.normal[1],
                c.normal[2], c.confidence, c.points, cpu);
    return 0;
  }
  catch (const std::exception& ex)
  {
    std::cerr << "stereo_contact_eval: " << ex.what() << std::endl;
    return 2;
  }
}
