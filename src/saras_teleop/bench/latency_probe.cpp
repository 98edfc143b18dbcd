// Benchmark probe for the running teleop nodes (see bench/run).
// Drives the master side at 1 kHz and timestamps every hop of the forward path
//   [UDP packet -> touchball_receiver -> TF] -> master_pose (tf_transformer) -> des_twist (transparency)
//      -> tank_twist (tank_slave) -> /mesa_left/target_pose (velocity_integrator)
// Every teleop node propagates the header stamp of the TF sample it processed, so the latency of a hop
// output = its receive time here - the TF sample's stamp (or - the UDP send time of the packet that
// produced that TF sample, matched through /touchball/left/state: stamp -> packet_seq).
// Modes:
//   tf              the probe publishes the master TF touch_left/base -> touch_left/stylus itself
//                   (stamp = send time): the teleop chain alone.
//   udp:PORT:CPORT  the probe sends real Touchball state packets (protocol v2, authenticated with the
//                   key $SARAS_KEY_DIR/console.key after the session handshake, saras_drivers
//                   docs/touchball_protocol.md) to the touchball_receiver on 127.0.0.1:PORT and drains
//                   its force commands on CPORT: the whole console-to-set-point path.
// Also publishes the static frames and a fake arm (/mesa_left/ee_pose = last target at 250 Hz), reports
// the achieved rate and period jitter of the 1 kHz outputs, and the core step costs.
// Usage: teleop_latency_probe [duration_s] [tf|udp:PORT:CPORT] [label]   |   teleop_latency_probe --core-only
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <openssl/evp.h>
#include <openssl/hmac.h>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>
#include <saras_msgs/HapticDeviceState.h>
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
  std::map<uint64_t, double> by_stamp;  // stamp (ns) -> first receive time
  std::vector<double> times;            // all receive times (for rate / jitter)
};

/// Everything the subscriber callbacks record (AsyncSpinner thread) and the sender reads.
struct Record
{
  std::mutex mutex;
  std::map<std::string, Arrivals> arr;
  std::map<uint64_t, double> sample;      // TF stamp (ns) -> TF sample time [s] (measured samples)
  std::map<uint64_t, uint32_t> seq_of;    // TF stamp (ns) -> packet seq (udp mode, /touchball/left/state)
  std::vector<double> udp_sent;           // packet seq -> UDP send time [s] (measured packets; 0 = not
                                          // measured); written by the sender thread only, read after it
                                          // stopped: no lock on the send path
};
Record g;

template <class M>
void record(const std::string& key, const M& m)
{
  const double now = ros::Time::now().toSec();
  std::lock_guard<std::mutex> lock(g.mutex);
  Arrivals& a = g.arr[key];
  a.times.push_back(now);
  a.by_stamp.emplace(m.header.stamp.toNSec(), now);
}

// ---- Touchball protocol v2 (saras_drivers docs/touchball_protocol.md), little-endian
/// The key of $SARAS_KEY_DIR/console.key (64..128 hex digits; '#' lines ignored); empty if unreadable.
std::vector<uint8_t> readKey()
{
  const char* dir = std::getenv("SARAS_KEY_DIR");
  std::ifstream f(std::string(dir ? dir : "/etc/saras") + "/console.key");
  std::string line;
  std::vector<uint8_t> key;
  while (std::getline(f, line))
  {
    if (line.empty() || line[0] == '#')
      continue;
    for (std::size_t i = 0; i + 1 < line.size() && std::isxdigit(static_cast<unsigned char>(line[i])); i += 2)
      key.push_back(static_cast<uint8_t>(std::stoul(line.substr(i, 2), nullptr, 16)));
    break;
  }
  return key;
}

std::vector<uint8_t> g_key;      ///< console link key
uint64_t g_session = 0;          ///< session nonce from the receiver's challenge

void sign(std::vector<uint8_t>& b)
{
  uint8_t mac[32];
  unsigned int len = 0;
  HMAC(EVP_sha256(), g_key.data(), static_cast<int>(g_key.size()), b.data(), b.size(), mac, &len);
  b.insert(b.end(), mac, mac + 16);
}

template <class T>
void put(std::vector<uint8_t>& b, T v)  // x86/ARM little-endian hosts
{
  const uint8_t* p = reinterpret_cast<const uint8_t*>(&v);
  b.insert(b.end(), p, p + sizeof(T));
}

/// Header '<4sBBHIdQ' of a v2 packet of @p type.
std::vector<uint8_t> header(uint8_t type, uint32_t seq, double sender_time, uint64_t session)
{
  std::vector<uint8_t> b;
  b.reserve(180);
  b.insert(b.end(), { 'T', 'B', 'A', 'L' });
  put<uint8_t>(b, 2);   // version
  put<uint8_t>(b, type);
  put<uint16_t>(b, 0);  // flags
  put<uint32_t>(b, seq);
  put<double>(b, sender_time);
  put<uint64_t>(b, session);
  return b;
}

/// Send hellos until the receiver's challenge (type 4, echoing @p nonce) gives the session.
bool handshake(int sock, int cmd_sock, const sockaddr_in& dst)
{
  std::mt19937_64 rng(std::random_device{}());
  const uint64_t nonce = rng() | 1u;
  timeval tv{ 0, 100000 };
  setsockopt(cmd_sock, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  for (int attempt = 0; attempt < 100 && ros::ok(); ++attempt)
  {
    std::vector<uint8_t> hello = header(3, 0, ros::WallTime::now().toSec(), nonce);
    sign(hello);
    (void)sendto(sock, hello.data(), hello.size(), 0, reinterpret_cast<const sockaddr*>(&dst), sizeof(dst));
    uint8_t buf[2048];
    const ssize_t n = recv(cmd_sock, buf, sizeof(buf), 0);
    uint64_t echo = 0;
    if (n == 52 && buf[5] == 4 && (std::memcpy(&echo, buf + 28, 8), echo == nonce))
    {
      std::memcpy(&g_session, buf + 20, 8);
      return true;
    }
  }
  return false;
}

/// 180-byte STATE packet: header, two devices '<3d4ddI' (left, right), 16-byte HMAC-SHA256 tag.
std::vector<uint8_t> statePacket(uint32_t seq, double sender_time, const double left_xyz[3], const double right_xyz[3])
{
  std::vector<uint8_t> b = header(1, seq, sender_time, g_session);
  for (const double* p : { left_xyz, right_xyz })
  {
    for (int i = 0; i < 3; ++i)
      put<double>(b, p[i]);
    for (double q : { 0.0, 0.0, 0.0, 1.0 })
      put<double>(b, q);
    put<double>(b, 0.0);    // clip angle
    put<uint32_t>(b, 0u);   // buttons: no clutch
  }
  sign(b);
  return b;
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

void printLatencyTable(const char* title, const std::vector<std::pair<std::string, std::string>>& hops,
                       const std::map<uint64_t, double>& origin)
{
  std::printf("\n%s, %zu samples sent:\n", title, origin.size());
  std::printf("| %-40s | %8s | %8s | %8s | %8s | %9s | %9s |\n", "hop (node -> topic)", "received", "p50 us", "p99 us",
              "max us", "hop p50 us", "hop p99 us");
  std::printf("|%s|%s|%s|%s|%s|%s|%s|\n", std::string(42, '-').c_str(), std::string(10, '-').c_str(),
              std::string(10, '-').c_str(), std::string(10, '-').c_str(), std::string(10, '-').c_str(),
              std::string(11, '-').c_str(), std::string(11, '-').c_str());
  for (std::size_t h = 0; h < hops.size(); ++h)
  {
    std::vector<double> lat, hop;
    for (const auto& kv : g.arr[hops[h].first].by_stamp)
    {
      auto o = origin.find(kv.first);
      if (o == origin.end())
        continue;  // warm-up sample or not matched to a measured packet
      lat.push_back((kv.second - o->second) * 1e6);
      if (h > 0)
      {
        const auto& prev = g.arr[hops[h - 1].first].by_stamp;
        auto it = prev.find(kv.first);
        if (it != prev.end())
          hop.push_back((kv.second - it->second) * 1e6);
      }
      else
      {
        hop.push_back((kv.second - o->second) * 1e6);
      }
    }
    std::printf("| %-40s | %8zu | %8.0f | %8.0f | %8.0f | %9.0f | %9.0f |\n", hops[h].second.c_str(), lat.size(),
                pct(lat, 50), pct(lat, 99), pct(lat, 100), pct(hop, 50), pct(hop, 99));
  }
}
}  // namespace

int main(int argc, char** argv)
{
  if (argc > 1 && std::string(argv[1]) == "--core-only")
  {
    coreCosts();
    return 0;
  }
  ros::init(argc, argv, "teleop_latency_probe");
  ros::NodeHandle nh;
  const double duration = argc > 1 ? std::atof(argv[1]) : 10.0;
  const std::string mode = argc > 2 ? argv[2] : "tf";
  const std::string label = argc > 3 ? argv[3] : "";
  // light: subscribe only /mesa_left/target_pose (as the SARAS arm driver does) so that the teleop
  // nodelets do not serialise every intermediate hop for this process (bench/run then times the hops
  // inside the manager with the LatencyRecorder nodelet)
  const bool light = argc > 4 && std::string(argv[4]) == "light";
  int udp_port = 0, cmd_port = 0;
  const bool udp = mode.compare(0, 4, "udp:") == 0;
  if (udp && std::sscanf(mode.c_str(), "udp:%d:%d", &udp_port, &cmd_port) != 2)
  {
    std::fprintf(stderr, "mode must be tf or udp:PORT:CPORT\n");
    return 2;
  }
  const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
  ros::Publisher tf_pub = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
  ros::Publisher static_pub = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 10, true);
  ros::Publisher ee_pub = nh.advertise<geometry_msgs::PoseStamped>("/mesa_left/ee_pose", 10);
  geometry_msgs::PoseStamped ee;
  ee.header.frame_id = "mesa_left/sbs_world";
  ee.pose.position.x = 0.3;
  ee.pose.orientation.w = 1.0;
  std::mutex ee_mutex;
  ros::Subscriber s0, s1, s2, s3, s5, s6;
  if (!light)
    s0 = nh.subscribe<saras_msgs::HapticDeviceState>(
      "/touchball/left/state", 1000,
      [](const saras_msgs::HapticDeviceState::ConstPtr& m) {
        record("0 touchball_state", *m);
        std::lock_guard<std::mutex> lock(g.mutex);
        g.seq_of[m->header.stamp.toNSec()] = m->packet_seq;
      },
      ros::VoidConstPtr(), fast);
  if (!light)
    s1 = nh.subscribe<geometry_msgs::PoseStamped>(
      "/teleop/left/master_pose", 1000, [](const geometry_msgs::PoseStamped::ConstPtr& m) { record("1 master_pose", *m); },
      ros::VoidConstPtr(), fast);
  if (!light)
    s2 = nh.subscribe<geometry_msgs::TwistStamped>(
      "/teleop/left/des_twist", 1000, [](const geometry_msgs::TwistStamped::ConstPtr& m) { record("2 des_twist", *m); },
      ros::VoidConstPtr(), fast);
  if (!light)
    s3 = nh.subscribe<geometry_msgs::TwistStamped>(
      "/teleop/left/tank_twist", 1000, [](const geometry_msgs::TwistStamped::ConstPtr& m) { record("3 tank_twist", *m); },
      ros::VoidConstPtr(), fast);
  auto s4 = nh.subscribe<geometry_msgs::PoseStamped>(
      "/mesa_left/target_pose", 1000,
      [&ee, &ee_mutex](const geometry_msgs::PoseStamped::ConstPtr& m) {
        record("4 target_pose", *m);
        std::lock_guard<std::mutex> lock(ee_mutex);
        ee.pose = m->pose;
      },
      ros::VoidConstPtr(), fast);
  if (!light)
    s5 = nh.subscribe<geometry_msgs::WrenchStamped>(
      "/touchball/left/wrench_cmd", 1000,
      [](const geometry_msgs::WrenchStamped::ConstPtr& m) { record("wrench_cmd", *m); }, ros::VoidConstPtr(), fast);
  if (!light)
    s6 = nh.subscribe<std_msgs::Float64>(
      "/teleop/tank_master/energy", 1000,
      [](const std_msgs::Float64::ConstPtr&) {
        const double now = ros::Time::now().toSec();
        std::lock_guard<std::mutex> lock(g.mutex);
        g.arr["tank_master/energy"].times.push_back(now);
      },
      ros::VoidConstPtr(), fast);

  tf2_msgs::TFMessage st;
  st.transforms.push_back(tf("world", "mesa_left/sbs_world", 0.0, 0.45, 0.0, -M_PI / 2));
  st.transforms.push_back(tf("world", "mesa_right/sbs_world", 0.0, -0.45, 0.0, M_PI / 2));
  st.transforms.push_back(tf("world", "console", -1.2, 0.0, 0.8, 0.0));
  st.transforms.push_back(tf("console", "touch_left/base", 0.0, 0.2, 0.0, 0.0));
  st.transforms.push_back(tf("console", "touch_right/base", 0.0, -0.2, 0.0, 0.0));
  static_pub.publish(st);

  // udp mode: socket to the receiver, and a socket that swallows its force commands
  int sock = -1, cmd_sock = -1;
  sockaddr_in dst{};
  if (udp)
  {
    sock = socket(AF_INET, SOCK_DGRAM, 0);
    cmd_sock = socket(AF_INET, SOCK_DGRAM, 0);
    dst.sin_family = AF_INET;
    dst.sin_port = htons(static_cast<uint16_t>(udp_port));
    dst.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    sockaddr_in c{};
    c.sin_family = AF_INET;
    c.sin_port = htons(static_cast<uint16_t>(cmd_port));
    c.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (sock < 0 || cmd_sock < 0 || bind(cmd_sock, reinterpret_cast<sockaddr*>(&c), sizeof(c)) != 0)
    {
      std::perror("teleop_latency_probe: udp sockets");
      return 2;
    }
    g_key = readKey();
    if (g_key.size() < 32 || !handshake(sock, cmd_sock, dst))
    {
      std::fprintf(stderr, "teleop_latency_probe: no console session (key $SARAS_KEY_DIR/console.key, %zu bytes)\n",
                   g_key.size());
      return 2;
    }
  }
  g.udp_sent.assign(static_cast<std::size_t>((duration + 3.0) * 1000.0) + 16, 0.0);  // 1 kHz, no allocation later
  std::atomic<bool> draining(udp);
  std::thread drain([&] {
    if (!udp)
      return;
    timeval tv{ 0, 100000 };
    setsockopt(cmd_sock, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
    uint8_t buf[2048];
    while (draining)
      (void)recv(cmd_sock, buf, sizeof(buf), 0);
  });

  ros::AsyncSpinner spinner(1);
  spinner.start();
  ros::WallDuration(2.0).sleep();  // connections
  const auto t_start = std::chrono::steady_clock::now();
  auto next = t_start;
  int k = 0;
  uint32_t seq = 0;
  double measure_from = 0.0;
  tf2_msgs::TFMessage dyn;
  dyn.transforms.push_back(tf("touch_left/base", "touch_left/stylus", 0, 0, 0.05, 0));
  const double right_xyz[3] = { -0.12, 0.0, 0.07 };
  while (ros::ok())
  {
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    if (t > duration + 2.0)
      break;
    const bool measuring = t > 2.0;  // first 2 s: warm-up (transparency waits for both poses, start pose)
    if (measuring && measure_from == 0.0)
      measure_from = ros::Time::now().toSec();
    const double x = 0.02 * std::sin(2 * M_PI * 0.3 * t);
    if (udp)
    {
      const double left_xyz[3] = { x, 0.0, 0.05 };
      // sender_time = wall-clock send time (as the real console sends): the in-manager
      // LatencyRecorder reads it from /touchball/left/state
      const double sent = ros::Time::now().toSec();
      const std::vector<uint8_t> pkt = statePacket(++seq, sent, left_xyz, right_xyz);
      (void)sendto(sock, pkt.data(), pkt.size(), 0, reinterpret_cast<const sockaddr*>(&dst), sizeof(dst));
      if (measuring && seq < g.udp_sent.size())
        g.udp_sent[seq] = sent;
    }
    else
    {
      auto& tr = dyn.transforms[0];
      tr.header.stamp = ros::Time::now();
      tr.transform.translation.x = x;
      if (measuring)
      {
        std::lock_guard<std::mutex> lock(g.mutex);
        g.sample[tr.header.stamp.toNSec()] = tr.header.stamp.toSec();
      }
      tf_pub.publish(dyn);
    }
    if (k % 4 == 0)
    {
      std::lock_guard<std::mutex> lock(ee_mutex);
      ee.header.stamp = ros::Time::now();
      ee_pub.publish(ee);
    }
    ++k;
    next += std::chrono::microseconds(1000);
    std::this_thread::sleep_until(next);
  }
  ros::WallDuration(0.3).sleep();
  spinner.stop();
  draining = false;
  drain.join();

  std::lock_guard<std::mutex> lock(g.mutex);
  const std::vector<std::pair<std::string, std::string>> chain = {
    { "1 master_pose", "tf_transformer -> master_pose" },
    { "2 des_twist", "transparency -> des_twist" },
    { "3 tank_twist", "tank_slave -> tank_twist" },
    { "4 target_pose", "velocity_integrator -> /mesa_left/target_pose" },
  };
  std::printf("\n== %s mode %s ==\n", label.c_str(), mode.c_str());
  if (light)
  {
    std::printf("\n(light probe: only /mesa_left/target_pose subscribed here; the hops are timed inside the "
                "manager by the LatencyRecorder nodelet, table below)\n");
  }
  else if (udp)
  {
    // TF stamp (= receiver's receive stamp) -> UDP send time / TF sample time of measured packets
    std::map<uint64_t, double> from_udp, from_tf;
    for (const auto& kv : g.seq_of)
    {
      if (kv.second >= g.udp_sent.size() || g.udp_sent[kv.second] == 0.0)
        continue;
      from_udp[kv.first] = g.udp_sent[kv.second];
      from_tf[kv.first] = kv.first * 1e-9;
    }
    std::printf("\nUDP packets sent in the window: %zu, matched to a receiver sample: %zu\n",
                static_cast<std::size_t>(std::count_if(g.udp_sent.begin(), g.udp_sent.end(), [](double x) { return x > 0.0; })),
                from_udp.size());
    std::vector<std::pair<std::string, std::string>> full = chain;
    full.insert(full.begin(), { "0 touchball_state", "touchball_receiver -> /touchball/left/state" });
    printLatencyTable("latency from the UDP packet send (touchball state packet) to each hop's output", full, from_udp);
    printLatencyTable("latency from the receiver's TF sample stamp to each hop's output", chain, from_tf);
  }
  else
  {
    printLatencyTable("latency from the master TF sample (stamp) to each hop's output", chain, g.sample);
  }

  std::printf("\noutput rate and period jitter (|period - 1 ms|) over the measurement window:\n");
  std::printf("| %-32s | %9s | %12s | %12s |\n", "topic", "rate Hz", "jitter p50 us", "jitter p99 us");
  std::printf("|%s|%s|%s|%s|\n", std::string(34, '-').c_str(), std::string(11, '-').c_str(),
              std::string(14, '-').c_str(), std::string(14, '-').c_str());
  for (const char* key : { "0 touchball_state", "1 master_pose", "4 target_pose", "wrench_cmd", "tank_master/energy" })
  {
    if ((!udp || light) && std::string(key) == "0 touchball_state")
      continue;
    if (light && std::string(key) != "4 target_pose")
      continue;
    std::vector<double> ts;
    for (double tt : g.arr[key].times)
      if (tt >= measure_from)
        ts.push_back(tt);
    std::vector<double> jit;
    for (std::size_t i = 1; i < ts.size(); ++i)
      jit.push_back(std::fabs(ts[i] - ts[i - 1] - 1e-3) * 1e6);
    const double rate = ts.size() > 1 ? (ts.size() - 1) / (ts.back() - ts.front()) : 0.0;
    std::printf("| %-32s | %9.1f | %12.0f | %12.0f |\n", key, rate, pct(jit, 50), pct(jit, 99));
  }
  if (sock >= 0)
    close(sock);
  if (cmd_sock >= 0)
    close(cmd_sock);
  if (label.find("nocore") == std::string::npos)
    coreCosts();
  return 0;
}
