// Benchmark probe for the running teleop nodes (see bench/run).
// Publishes the master TF touch_left/stylus at 1 kHz (stamp = send time) plus the static frames and a
// fake arm (/mesa_left/ee_pose = last target), and timestamps every hop of the forward path:
//   TF -> master_pose (tf_transformer) -> des_twist (transparency) -> tank_twist (tank_slave)
//      -> /mesa_left/target_pose (velocity_integrator)
// Every node propagates the header stamp of the sample it processed, so latency = receive - stamp.
// Also reports the achieved rate and period jitter of the 1 kHz outputs, and the core step costs.
// Usage: teleop_latency_probe [duration_s]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <thread>
#include <string>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>
#include <std_msgs/Float64.h>
#include <tf2_msgs/TFMessage.h>

#include "saras_teleop/energy_tank.h"
#include "saras_teleop/transparency.h"
#include "saras_teleop/twist_estimator.h"
#include "saras_teleop/velocity_integrator.h"

namespace
{
double pct(std::vector<double> v, double p)
{
  if (v.empty())
    return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(p / 100.0 * (v.size() - 1) + 0.5));
  return v[i];
}

struct Arrivals
{
  std::map<uint64_t, double> by_stamp;  // stamp (ns) -> receive time
  std::vector<double> times;            // all receive times (for rate / jitter)
};

std::map<std::string, Arrivals> g_arr;
std::map<uint64_t, double> g_sent;  // stamp ns -> send time

template <class M>
void record(const std::string& key, const M& m)
{
  const double now = ros::Time::now().toSec();
  Arrivals& a = g_arr[key];
  a.times.push_back(now);
  const uint64_t s = m.header.stamp.toNSec();
  if (g_sent.count(s) && !a.by_stamp.count(s))
    a.by_stamp[s] = now;
}

geometry_msgs::TransformStamped tf(const std::string& p, const std::string& c, double x, double y, double z,
                                   double yaw)
{
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = p;
  t.child_frame_id = c;
  t.transform.translation.x = x;
  t.transform.translation.y = y;
  t.transform.translation.z = z;
  t.transform.rotation.z = std::sin(yaw / 2);
  t.transform.rotation.w = std::cos(yaw / 2);
  return t;
}

template <class F>
double nsPerCall(F&& f, int n)
{
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i)
    f(i);
  const auto t1 = std::chrono::steady_clock::now();
  return std::chrono::duration<double, std::nano>(t1 - t0).count() / n;
}

void coreCosts()
{
  using namespace saras_teleop;
  EnergyTank tank(TankParams(), 2);
  Vector6d a = Vector6d::Constant(0.3), m = Vector6d::Constant(0.01);
  const double t_tank = nsPerCall(
      [&](int i) {
        m[0] = 0.01 * (i % 7);
        tank.setDesired(0, a);
        tank.setConjugate(0, m);
        tank.setDesired(1, a);
        tank.setConjugate(1, m);
        tank.step(0.001, 0.1, 0.0);
      },
      1000000);
  TransparencyChannel tr(TransparencyParams{});
  tr.setSlavePosition(Eigen::Vector3d::Zero());
  Vector6d w, v;
  const double t_tr = nsPerCall(
      [&](int i) {
        tr.setMasterPosition(Eigen::Vector3d(1e-6 * i, 0, 0));
        tr.update(w, v);
      },
      1000000);
  TwistEstimator est(50.0, 0.1);
  const double t_est =
      nsPerCall([&](int i) { est.addSample(i * 1e-3, KDL::Frame(KDL::Rotation::RotZ(1e-4 * i), KDL::Vector(1e-6 * i, 0, 0))); },
                1000000);
  VelocityIntegrator vi{ IntegratorParams() };
  vi.start(KDL::Frame::Identity());
  const double t_vi = nsPerCall([&](int i) { vi.step(Vector6d::Constant(1e-3 * (i % 3)), 1e-3, false); }, 1000000);
  std::printf("\ncore step cost (single thread, no ROS):\n");
  std::printf("| %-34s | %10s |\n", "core operation", "ns / call");
  std::printf("|%s|%s|\n", std::string(36, '-').c_str(), std::string(12, '-').c_str());
  std::printf("| %-34s | %10.0f |\n", "EnergyTank::step (2 ports)", t_tank);
  std::printf("| %-34s | %10.0f |\n", "TransparencyChannel::update", t_tr);
  std::printf("| %-34s | %10.0f |\n", "TwistEstimator::addSample", t_est);
  std::printf("| %-34s | %10.0f |\n", "VelocityIntegrator::step", t_vi);
}
}  // namespace

int main(int argc, char** argv)
{
  ros::init(argc, argv, "teleop_latency_probe");
  ros::NodeHandle nh;
  const double duration = argc > 1 ? std::atof(argv[1]) : 10.0;
  const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
  ros::Publisher tf_pub = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
  ros::Publisher static_pub = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 10, true);
  ros::Publisher ee_pub = nh.advertise<geometry_msgs::PoseStamped>("/mesa_left/ee_pose", 10);
  geometry_msgs::PoseStamped ee;
  ee.header.frame_id = "mesa_left/sbs_world";
  ee.pose.position.x = 0.3;
  ee.pose.orientation.w = 1.0;
  auto s1 = nh.subscribe<geometry_msgs::PoseStamped>(
      "/teleop/left/master_pose", 1000, [](const geometry_msgs::PoseStamped::ConstPtr& m) { record("1 master_pose", *m); },
      ros::VoidConstPtr(), fast);
  auto s2 = nh.subscribe<geometry_msgs::TwistStamped>(
      "/teleop/left/des_twist", 1000, [](const geometry_msgs::TwistStamped::ConstPtr& m) { record("2 des_twist", *m); },
      ros::VoidConstPtr(), fast);
  auto s3 = nh.subscribe<geometry_msgs::TwistStamped>(
      "/teleop/left/tank_twist", 1000, [](const geometry_msgs::TwistStamped::ConstPtr& m) { record("3 tank_twist", *m); },
      ros::VoidConstPtr(), fast);
  auto s4 = nh.subscribe<geometry_msgs::PoseStamped>(
      "/mesa_left/target_pose", 1000,
      [&ee](const geometry_msgs::PoseStamped::ConstPtr& m) {
        record("4 target_pose", *m);
        ee.pose = m->pose;
      },
      ros::VoidConstPtr(), fast);
  auto s5 = nh.subscribe<geometry_msgs::WrenchStamped>(
      "/touchball/left/wrench_cmd", 1000,
      [](const geometry_msgs::WrenchStamped::ConstPtr& m) { g_arr["wrench_cmd"].times.push_back(ros::Time::now().toSec()); (void)m; },
      ros::VoidConstPtr(), fast);
  auto s6 = nh.subscribe<std_msgs::Float64>(
      "/teleop/tank_master/energy", 1000,
      [](const std_msgs::Float64::ConstPtr&) { g_arr["tank_master/energy"].times.push_back(ros::Time::now().toSec()); },
      ros::VoidConstPtr(), fast);

  tf2_msgs::TFMessage st;
  st.transforms.push_back(tf("world", "mesa_left/sbs_world", 0.0, 0.45, 0.0, -M_PI / 2));
  st.transforms.push_back(tf("world", "mesa_right/sbs_world", 0.0, -0.45, 0.0, M_PI / 2));
  st.transforms.push_back(tf("world", "console", -1.2, 0.0, 0.8, 0.0));
  st.transforms.push_back(tf("console", "touch_left/base", 0.0, 0.2, 0.0, 0.0));
  st.transforms.push_back(tf("console", "touch_right/base", 0.0, -0.2, 0.0, 0.0));
  static_pub.publish(st);

  ros::AsyncSpinner spinner(1);
  spinner.start();
  ros::WallDuration(2.0).sleep();  // connections
  const auto t_start = std::chrono::steady_clock::now();
  auto next = t_start;
  int k = 0;
  double measure_from = 0.0;
  tf2_msgs::TFMessage dyn;
  dyn.transforms.push_back(tf("touch_left/base", "touch_left/stylus", 0, 0, 0.05, 0));
  while (ros::ok())
  {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    if (t > duration + 2.0)
      break;
    auto& x = dyn.transforms[0];
    x.header.stamp = ros::Time::now();
    x.transform.translation.x = 0.02 * std::sin(2 * M_PI * 0.3 * t);
    if (t > 2.0)  // first 2 s: warm-up (transparency waits for both poses, start pose)
    {
      if (measure_from == 0.0)
        measure_from = ros::Time::now().toSec();
      g_sent[x.header.stamp.toNSec()] = x.header.stamp.toSec();
    }
    tf_pub.publish(dyn);
    if (k % 4 == 0)
    {
      ee.header.stamp = ros::Time::now();
      ee_pub.publish(ee);
    }
    ++k;
    next += std::chrono::microseconds(1000);
    std::this_thread::sleep_until(next);
  }
  ros::WallDuration(0.2).sleep();
  spinner.stop();

  std::printf("\nend-to-end latency from the master TF sample (stamp) to each hop's output, %zu samples sent:\n",
              g_sent.size());
  std::printf("| %-36s | %8s | %8s | %8s | %8s | %9s |\n", "hop (node -> topic)", "received", "p50 us", "p99 us",
              "max us", "hop p99 us");
  std::printf("|%s|%s|%s|%s|%s|%s|\n", std::string(38, '-').c_str(), std::string(10, '-').c_str(),
              std::string(10, '-').c_str(), std::string(10, '-').c_str(), std::string(10, '-').c_str(),
              std::string(11, '-').c_str());
  const char* names[] = { "1 master_pose", "2 des_twist", "3 tank_twist", "4 target_pose" };
  const char* labels[] = { "tf_transformer -> master_pose", "transparency -> des_twist", "tank_slave -> tank_twist",
                           "velocity_integrator -> target_pose" };
  for (int h = 0; h < 4; ++h)
  {
    std::vector<double> lat, hop;
    for (const auto& kv : g_arr[names[h]].by_stamp)
    {
      lat.push_back((kv.second - g_sent[kv.first]) * 1e6);
      if (h > 0)
      {
        const auto& prev = g_arr[names[h - 1]].by_stamp;
        auto it = prev.find(kv.first);
        if (it != prev.end())
          hop.push_back((kv.second - it->second) * 1e6);
      }
      else
      {
        hop.push_back((kv.second - g_sent[kv.first]) * 1e6);
      }
    }
    std::printf("| %-36s | %8zu | %8.0f | %8.0f | %8.0f | %9.0f |\n", labels[h], lat.size(), pct(lat, 50), pct(lat, 99),
                pct(lat, 100), pct(hop, 99));
  }

  std::printf("\noutput rate and period jitter (|period - 1 ms|) over the measurement window:\n");
  std::printf("| %-32s | %9s | %12s | %12s |\n", "topic", "rate Hz", "jitter p50 us", "jitter p99 us");
  std::printf("|%s|%s|%s|%s|\n", std::string(34, '-').c_str(), std::string(11, '-').c_str(),
              std::string(14, '-').c_str(), std::string(14, '-').c_str());
  for (const char* key : { "1 master_pose", "4 target_pose", "wrench_cmd", "tank_master/energy" })
  {
    std::vector<double> ts;
    for (double t : g_arr[key].times)
      if (t >= measure_from)
        ts.push_back(t);
    std::vector<double> jit;
    for (std::size_t i = 1; i < ts.size(); ++i)
      jit.push_back(std::fabs(ts[i] - ts[i - 1] - 1e-3) * 1e6);
    const double rate = ts.size() > 1 ? (ts.size() - 1) / (ts.back() - ts.front()) : 0.0;
    std::printf("| %-32s | %9.1f | %12.0f | %12.0f |\n", key, rate, pct(jit, 50), pct(jit, 99));
  }
  coreCosts();
  return 0;
}
