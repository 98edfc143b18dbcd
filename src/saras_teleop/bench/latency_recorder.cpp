/**
 * @file latency_recorder.cpp
 * @brief Benchmark nodelet saras_teleop/LatencyRecorder (bench/run only, not part of the platform).
 *
 * Loaded into the teleop manager next to the Touchball receiver and the teleop nodelets, it
 * subscribes to the hop outputs of the left channel in-process (zero-copy: no serialisation, no TCP)
 * and records when each message reaches a subscriber in the manager, i.e. when the set-point is
 * available to a consumer nodelet, without the TCP delivery to an external probe process:
 *   /touchball/left/state (receiver), /teleop/left/master_pose (tf_transformer), /teleop/left/des_twist
 *   (transparency), /teleop/left/tank_twist (tank_slave), /mesa_left/target_pose (velocity_integrator).
 * Every hop propagates the receiver's header stamp; the state message carries the packet's sender_time,
 * which the probe (teleop_latency_probe udp mode) sets to the wall-clock time just before sendto().
 * So for every packet: UDP send -> receiver stamp -> each hop's in-manager arrival.
 * After ~duration [s] of samples (from the first state message after ~warmup [s]) it writes the table
 * (p50/p99/max end-to-end and per hop) to ~output and stops recording.
 */
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <saras_msgs/HapticDeviceState.h>

namespace saras_teleop
{
namespace bench
{
class LatencyRecorder : public nodelet::Nodelet
{
  static constexpr int kHops = 5;

  void onInit() override
  {
    // ~callback_thread: `own` (default): arrivals are taken on a thread of its own (a ros::AsyncSpinner
    // on a private queue: one wake-up per observation), not through the manager's two-step dispatch,
    // so the recorder adds no hand-off of the manager to what it measures; `shared`: on the global callback queue, i.e. the
    // thread that runs the teleop nodes with callback_thread `shared` (NodeletAdapter): each
    // arrival is then the instant the chain's own executor reaches that output, with no wake-up of
    // the recorder in it.
    ros::NodeHandle nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    std::string mode;
    pnh.param<std::string>("callback_thread", mode, "own");
    if (mode != "own" && mode != "shared")
      throw std::invalid_argument("parameter ~callback_thread must be own or shared, got '" + mode + "'");
    own_thread_ = mode == "own";
    nh.setCallbackQueue(own_thread_ ? &queue_ : ros::getGlobalCallbackQueue());
    pnh.param("duration", duration_, 10.0);
    pnh.param("warmup", warmup_, 2.0);
    pnh.param<std::string>("output", output_, "/tmp/teleop_latency_recorder.txt");
    const std::size_t n = static_cast<std::size_t>((duration_ + warmup_ + 5.0) * 1000.0);
    for (auto& h : arrivals_)
      h.reserve(n);
    const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
    subs_.push_back(nh.subscribe<saras_msgs::HapticDeviceState>(
        "/touchball/left/state", 100,
        [this](const saras_msgs::HapticDeviceState::ConstPtr& m) {
          if (!m->stale)
            add(0, m->header.stamp, m->sender_time);
        },
        ros::VoidConstPtr(), fast));
    subs_.push_back(nh.subscribe<geometry_msgs::PoseStamped>(
        "/teleop/left/master_pose", 100,
        [this](const geometry_msgs::PoseStamped::ConstPtr& m) { add(1, m->header.stamp); }, ros::VoidConstPtr(), fast));
    subs_.push_back(nh.subscribe<geometry_msgs::TwistStamped>(
        "/teleop/left/des_twist", 100,
        [this](const geometry_msgs::TwistStamped::ConstPtr& m) { add(2, m->header.stamp); }, ros::VoidConstPtr(), fast));
    subs_.push_back(nh.subscribe<geometry_msgs::TwistStamped>(
        "/teleop/left/tank_twist", 100,
        [this](const geometry_msgs::TwistStamped::ConstPtr& m) { add(3, m->header.stamp); }, ros::VoidConstPtr(), fast));
    subs_.push_back(nh.subscribe<geometry_msgs::PoseStamped>(
        "/mesa_left/target_pose", 100,
        [this](const geometry_msgs::PoseStamped::ConstPtr& m) { add(4, m->header.stamp); }, ros::VoidConstPtr(), fast));
    if (own_thread_)
    {
      spinner_.reset(new ros::AsyncSpinner(1, &queue_));
      spinner_->start();
    }
  }

public:
  ~LatencyRecorder() override
  {
    if (spinner_)
      spinner_->stop();
    std::lock_guard<std::mutex> lock(mutex_);
    if (!done_ && t_first_ > 0.0)  // unloaded before the window ended: write what was recorded
      write();
  }

private:
  struct Sample
  {
    std::uint64_t stamp;  ///< receiver stamp [ns] (propagated by every hop)
    double arrival;       ///< [s] ROS (wall) time at the callback
    double sent;          ///< [s] UDP send time (state messages only)
  };

  void add(int hop, const ros::Time& stamp, double sent = 0.0)
  {
    const double now = ros::Time::now().toSec();
    std::lock_guard<std::mutex> lock(mutex_);
    if (done_)
      return;
    if (t_first_ == 0.0)
      t_first_ = now;
    if (now - t_first_ < warmup_)
      return;
    if (now - t_first_ > warmup_ + duration_)
    {
      done_ = true;
      write();
      return;
    }
    if (arrivals_[hop].size() < arrivals_[hop].capacity())
      arrivals_[hop].push_back(Sample{ stamp.toNSec(), now, sent });
  }

  static double pct(std::vector<double> v, double p)
  {
    if (v.empty())
      return 0.0 / 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, static_cast<std::size_t>(p / 100.0 * (v.size() - 1) + 0.5))];
  }

  void write()
  {
    static const char* names[kHops] = { "touchball_receiver -> /touchball/left/state", "tf_transformer -> master_pose",
                                        "transparency -> des_twist", "tank_slave -> tank_twist",
                                        "velocity_integrator -> /mesa_left/target_pose" };
    std::map<std::uint64_t, double> sent, prev;
    std::vector<double> stamp_lat;
    for (const Sample& s : arrivals_[0])
    {
      sent[s.stamp] = s.sent;
      stamp_lat.push_back((s.stamp * 1e-9 - s.sent) * 1e6);
    }
    FILE* f = std::fopen(output_.c_str(), "w");
    if (!f)
    {
      ROS_ERROR("latency_recorder: cannot write %s", output_.c_str());
      return;
    }
    std::fprintf(f, "in-manager arrival (LatencyRecorder nodelet, zero-copy) of each hop's output, from the UDP send of "
                    "the packet, %zu packets:\n",
                 sent.size());
    std::fprintf(f, "| %-46s | %8s | %8s | %8s | %8s | %10s | %10s |\n", "hop (node -> topic)", "received", "p50 us",
                 "p99 us", "max us", "hop p50 us", "hop p99 us");
    std::fprintf(f, "|%s|%s|%s|%s|%s|%s|%s|\n", std::string(48, '-').c_str(), std::string(10, '-').c_str(),
                 std::string(10, '-').c_str(), std::string(10, '-').c_str(), std::string(10, '-').c_str(),
                 std::string(12, '-').c_str(), std::string(12, '-').c_str());
    std::fprintf(f, "| %-46s | %8zu | %8.0f | %8.0f | %8.0f | %10s | %10s |\n", "UDP send -> receiver stamp",
                 stamp_lat.size(), pct(stamp_lat, 50), pct(stamp_lat, 99), pct(stamp_lat, 100), "", "");
    for (int h = 0; h < kHops; ++h)
    {
      std::vector<double> lat, hop;
      std::map<std::uint64_t, double> cur;
      for (const Sample& s : arrivals_[h])
      {
        auto it = sent.find(s.stamp);
        if (it == sent.end() || cur.count(s.stamp))
          continue;  // not a measured packet, or a watchdog republication of the same sample
        cur[s.stamp] = s.arrival;
        lat.push_back((s.arrival - it->second) * 1e6);
        auto p = h <= 1 ? cur.end() : prev.find(s.stamp);
        if (h <= 1)  // receiver stamp -> state arrival / TF -> tf_transformer -> master_pose arrival
          hop.push_back((s.arrival - s.stamp * 1e-9) * 1e6);
        else if (p != prev.end())
          hop.push_back((s.arrival - p->second) * 1e6);
      }
      std::fprintf(f, "| %-46s | %8zu | %8.0f | %8.0f | %8.0f | %10.0f | %10.0f |\n", names[h], lat.size(),
                   pct(lat, 50), pct(lat, 99), pct(lat, 100), pct(hop, 50), pct(hop, 99));
      prev.swap(cur);
    }
    std::fclose(f);
  }

  std::mutex mutex_;
  bool own_thread_ = true;  ///< arrivals on queue_, served by spinner_ (else on the global queue)
  ros::CallbackQueue queue_;  // declared before subs_: destroyed after them
  std::unique_ptr<ros::AsyncSpinner> spinner_;
  std::vector<ros::Subscriber> subs_;
  std::vector<Sample> arrivals_[kHops];
  double duration_ = 10.0, warmup_ = 2.0, t_first_ = 0.0;
  bool done_ = false;
  std::string output_;
};

}  // namespace bench
}  // namespace saras_teleop

PLUGINLIB_EXPORT_CLASS(saras_teleop::bench::LatencyRecorder, nodelet::Nodelet)
