/**
 * @file touchball_receiver_nodelet.cpp
 * @brief Nodelet saras_drivers/TouchballReceiver: ROS side of the Touchball console link (UDP).
 *
 * ROS wiring only: parameters in, publishers, subscribers, timers, /diagnostics. The socket is a
 * UdpSocket, the link state shared between the receive thread and the callback queue a
 * ReceiverCore (validation, watchdog, force latches, counters), both ROS-free
 * (touchball_udp.h, touchball_receiver_core.h, gtests in test/touchball/).
 *
 * Listens on ~bind_address:~port for authenticated state packets (protocol v2,
 * docs/touchball_protocol.md) from ~allowed_source, keyed by ~key_file (mode 0600; missing or
 * readable by others => fatal start-up error naming the file). A console's hello is answered with
 * a challenge carrying the session nonce (when no session streams). The receive thread waits in ppoll() for a datagram or the watchdog deadline
 * (no busy loop) and publishes every accepted packet at once, from preallocated pooled messages
 * (boost::shared_ptr: zero-copy to nodelets in the same manager, e.g. the teleoperation's
 * tf_transformer), in this order (the teleoperation path first):
 *
 *   touchball/tf              tf2_msgs/TFMessage: touch_<side>/base -> touch_<side>/stylus, both sides in
 *                             one message (the teleoperation's tf_transformers listen here: remap /tf)
 *   touchball/<side>/state    saras_msgs/HapticDeviceState (frame touch_<side>/base)
 *   touchball/<side>/pose     geometry_msgs/PoseStamped
 *   touchball/<side>/twist    geometry_msgs/TwistStamped   [m/s, rad/s] in touch_<side>/base
 *
 * The same stylus TF goes to /tf at ~tf_rate only (rviz, the recording and the platform's other TF
 * listeners, which would otherwise each deserialise 1000 TF messages/s; the state topics carry every
 * sample). touchball/<side>/buttons (sensor_msgs/Joy, latched: buttons [clutch, clip], axes [clip angle
 * rad] at that packet) is published when a button changes (and at the first packet), as the dVRK's
 * button events.
 *
 * and answers each accepted packet with a command packet (sent before the non-TF topics) carrying
 * the latest touchball/<side>/wrench_cmd (geometry_msgs/WrenchStamped in touch_<side>/base, TCP_NODELAY;
 * older than ~wrench_timeout, NaN or another frame => zero force).
 *
 * Link status for the teleoperation: touchball/status (saras_msgs/ComponentStatus, OK / STALE,
 * consumed as link_status by saras_teleop, which holds on STALE) at ~status_rate plus immediately
 * on change. Watchdog: no valid packet for ~timeout => STALE status first (consumers hold), then one
 * stale state per side, published by the receive thread at the deadline itself.
 * Health: /diagnostics (diagnostic_updater, hardware_id console_link, status "<node>: console link")
 * every ~diagnostic_period (1 s) and on every OK/STALE change: packet rate, input age, counters per
 * rejection reason (keys: describeHealth() in touchball_receiver_core.h); rejection log lines at most
 * one per second per reason, with the count of the ones not logged.
 * touch_<side>/joint_states (sensor_msgs/JointState, rviz) at ~joint_states_rate.
 * The wrench_cmd callbacks run in the publisher's thread (saras_common::InlineCallbackQueue).
 * Header stamps are the receive time (ros::Time::now()). Parameters: config/touchball.yaml (units
 * there), read once by readReceiverConfig (saras_common::Params); an invalid value is a fatal
 * start-up error naming the parameter (`nodelet standalone` / `nodelet load` exit non-zero).
 * Per-packet messages come from saras_common::MessagePool (no allocation on the receive path).
 */
#include <pthread.h>
#include <sched.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <diagnostic_updater/diagnostic_updater.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <saras_common/message_pool.h>
#include <saras_common/params.h>
#include <saras_msgs/ComponentStatus.h>
#include <saras_msgs/HapticDeviceState.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/Joy.h>
#include <tf2_msgs/TFMessage.h>

#include "saras_common/inline_callback_queue.h"
#include "saras_common/nodelet_namespace.h"
#include "saras_drivers/touchball_kinematics.h"
#include "saras_drivers/touchball_receiver_core.h"
#include "saras_drivers/touchball_receiver_params.h"
#include "saras_drivers/touchball_udp.h"

namespace saras_drivers
{
namespace touchball
{
namespace
{
constexpr std::size_t kRecvBuffer = 2048;  ///< [bytes] > any packet: oversized datagrams stay detectable
constexpr double kIdleWake = 0.1;          ///< [s] receive-thread wake-up while STALE (shutdown)
constexpr double kStuckFactor = 3.0;       ///< stalled receive thread: no packet handled for this x timeout
constexpr std::size_t kPoolSize = 16;      ///< messages per topic pool (> in-process subscriber backlog)

double monotonic()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double wallTime()
{
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

void setRealtime(int prio)
{
  if (prio <= 0)
    return;
  sched_param sp{};
  sp.sched_priority = prio;
  const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
  if (err == 0)
    ROS_INFO("touchball_receiver: receive thread at SCHED_FIFO priority %d", prio);
  else
    ROS_WARN("touchball_receiver: cannot set ~realtime_priority %d (%s): normal scheduling, the watchdog and "
             "latency then depend on the host load (grant CAP_SYS_NICE or an rtprio limit, or set it to 0)",
             prio, std::strerror(err));
}
}  // namespace

/**
 * One Touchball console link: publishers, subscribers, timers and the receive thread around a
 * ReceiverCore and a UdpSocket. Threads: the receive thread (decode, publish, command, watchdog)
 * and the nodelet's callback queue (wrench_cmd subscriptions, status, diagnostics and joint_states
 * timers). status_mutex_ orders the receive thread's STALE/OK decisions with the periodic
 * touchball/status, so a consumer never sees an older decision after a newer one.
 */
class TouchballReceiver
{
public:
  /// @param ns namespace of the node (absolute, ending in '/'): the topics are <ns>touchball/...
  TouchballReceiver(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& ns, const std::string& name)
    : cfg_(readReceiverConfig(saras_common::Params(pnh)))
    , core_(cfg_.link, cfg_.wrench, readKeyFile(cfg_.key_file), kStuckFactor)
    , socket_(cfg_.bind_address, cfg_.port)
    , updater_(nh, pnh, name)
  {
    std::snprintf(source_, sizeof source_, "%s:%u", cfg_.link.any_source ? "*" : cfg_.allowed_source.c_str(),
                  static_cast<unsigned>(cfg_.port));
    advertise(nh, ns);
    updater_.setHardwareID("console_link");
    updater_.add("console link", this, &TouchballReceiver::diagnose);
    status_timer_ = nh.createSteadyTimer(ros::WallDuration(1.0 / cfg_.status_rate), &TouchballReceiver::onStatusTimer, this);
    if (cfg_.joint_states_rate > 0.0)
      js_timer_ = nh.createSteadyTimer(ros::WallDuration(1.0 / cfg_.joint_states_rate),
                                       &TouchballReceiver::onJointTimer, this);
    ROS_INFO("touchball_receiver: listening on %s:%d, accepting %s, watchdog %.0f ms, protocol v%d keyed by %s",
             cfg_.bind_address.c_str(), cfg_.port, cfg_.link.any_source ? "any source" : cfg_.allowed_source.c_str(),
             1e3 * cfg_.link.timeout, kVersion, cfg_.key_file.c_str());
    running_ = true;
    thread_ = std::thread(&TouchballReceiver::run, this);
  }

  ~TouchballReceiver()
  {
    running_ = false;
    if (thread_.joinable())
      thread_.join();  // wakes within kIdleWake or the watchdog deadline
  }

private:
  struct Side
  {
    ros::Publisher pub_state, pub_pose, pub_twist, pub_buttons, pub_js;
    std::int64_t buttons = -1;  ///< bit mask last published on pub_buttons (-1: none yet)
    ros::Subscriber sub_wrench;
    std::unique_ptr<saras_common::MessagePool<saras_msgs::HapticDeviceState>> state;
    std::unique_ptr<saras_common::MessagePool<geometry_msgs::PoseStamped>> pose;
    std::unique_ptr<saras_common::MessagePool<geometry_msgs::TwistStamped>> twist;
    std::unique_ptr<saras_common::MessagePool<sensor_msgs::Joy>> joy;
    sensor_msgs::JointState js;  ///< joint_states timer only
  };

  // ------------------------------------------------------------------ set-up
  void advertise(ros::NodeHandle& nh, const std::string& ns)
  {
    const unsigned qs = cfg_.publish_queue_size > 0 ? static_cast<unsigned>(cfg_.publish_queue_size) : 100u;
    tf2_msgs::TFMessage tf;
    for (int i = 0; i < kDevices; ++i)
    {
      const std::string side = kDeviceNames[i];
      const std::string tns = ns + "touchball/" + side + "/";
      frames_[i] = "touch_" + side + "/base";
      Side& s = sides_[i];
      s.pub_state = nh.advertise<saras_msgs::HapticDeviceState>(tns + "state", qs);
      s.pub_pose = nh.advertise<geometry_msgs::PoseStamped>(tns + "pose", qs);
      s.pub_twist = nh.advertise<geometry_msgs::TwistStamped>(tns + "twist", qs);
      s.pub_buttons = nh.advertise<sensor_msgs::Joy>(tns + "buttons", qs, true);
      makeRings(i, s);
      geometry_msgs::TransformStamped tr;
      tr.header.frame_id = frames_[i];
      tr.child_frame_id = "touch_" + side + "/stylus";
      tr.transform.rotation.w = 1.0;
      tf.transforms.push_back(tr);
      if (cfg_.joint_states_rate > 0.0)
      {
        s.pub_js = nh.advertise<sensor_msgs::JointState>(ns + "touch_" + side + "/joint_states", 10);
        for (const char* n : kTouchJointNames)
          s.js.name.push_back("touch_" + side + "/" + n);
        s.js.position.assign(6, 0.0);
      }
      const ros::TransportHints fast = ros::TransportHints().tcpNoDelay();
      // onWrench only latches the command (ReceiverCore, locked): it runs at once in the publisher's
      // thread (the teleoperation's, in the same manager), not on a worker thread woken per message
      ros::SubscribeOptions ops;
      ops.init<geometry_msgs::WrenchStamped>(
          tns + "wrench_cmd", 10, [this, i](const geometry_msgs::WrenchStamped::ConstPtr& m) { onWrench(i, *m); });
      ops.transport_hints = fast;
      ops.callback_queue = &wrench_queue_;
      s.sub_wrench = nh.subscribe(ops);
    }
    tf_.reset(new saras_common::MessagePool<tf2_msgs::TFMessage>(kPoolSize, tf));
    if (cfg_.publish_tf)
    {
      pub_tf_ = nh.advertise<tf2_msgs::TFMessage>("/tf", qs);
      pub_tf_all_ = nh.advertise<tf2_msgs::TFMessage>(ns + "touchball/tf", qs);
      tf_period_ = ros::Duration(cfg_.tf_rate > 0.0 ? 1.0 / cfg_.tf_rate : 0.0);
    }
    pub_status_ = nh.advertise<saras_msgs::ComponentStatus>(ns + "touchball/status", 10);
  }

  void makeRings(int i, Side& s)
  {
    saras_msgs::HapticDeviceState st;
    st.header.frame_id = frames_[i];
    st.device = kDeviceNames[i];
    st.pose.orientation.w = 1.0;
    st.stale = true;
    s.state.reset(new saras_common::MessagePool<saras_msgs::HapticDeviceState>(kPoolSize, st));
    geometry_msgs::PoseStamped pose;
    pose.header.frame_id = frames_[i];
    s.pose.reset(new saras_common::MessagePool<geometry_msgs::PoseStamped>(kPoolSize, pose));
    geometry_msgs::TwistStamped twist;
    twist.header.frame_id = frames_[i];
    s.twist.reset(new saras_common::MessagePool<geometry_msgs::TwistStamped>(kPoolSize, twist));
    sensor_msgs::Joy joy;
    joy.header.frame_id = frames_[i];
    joy.axes.assign(1, 0.0f);
    joy.buttons.assign(2, 0);
    s.joy.reset(new saras_common::MessagePool<sensor_msgs::Joy>(kPoolSize, joy));
  }

  // ------------------------------------------------------------------ ROS inputs (callback queue)
  void onWrench(int i, const geometry_msgs::WrenchStamped& m)
  {
    if (m.header.frame_id != frames_[i])
    {
      core_.rejectWrench(i);
      ROS_ERROR_THROTTLE(1.0, "touchball_receiver: wrench_cmd frame '%s' != '%s', zero force",
                         m.header.frame_id.c_str(), frames_[i].c_str());
      return;
    }
    const auto& f = m.wrench.force;
    const auto& t = m.wrench.torque;
    const double force[3] = { f.x, f.y, f.z }, torque[3] = { t.x, t.y, t.z };
    if (!core_.setWrench(i, force, torque, monotonic()))
      ROS_ERROR_THROTTLE(1.0, "touchball_receiver: non-finite wrench_cmd on %s, zero force", kDeviceNames[i]);
  }

  // ------------------------------------------------------------------ receive thread
  void run()
  {
    pthread_setname_np(pthread_self(), "touchball_rx");  // visible in top -H, /proc/<pid>/task/*/comm
    setRealtime(cfg_.realtime_priority);
    std::array<std::uint8_t, kRecvBuffer> buf;
    while (running_ && ros::ok())
    {
      const double wait = core_.waitTime(monotonic(), kIdleWake);
      // deadline passed (thread descheduled): still look at what is queued first
      const int ready = wait > 0.0 ? socket_.wait(wait) : 1;
      if (ready < 0)
        ROS_ERROR_THROTTLE(1.0, "touchball_receiver: poll error: %s", std::strerror(-ready));
      Endpoint src;
      const long n = ready > 0 ? socket_.receive(buf.data(), buf.size(), src) : -EAGAIN;
      if (n < 0 && n != -EAGAIN)
        ROS_ERROR_THROTTLE(1.0, "touchball_receiver: socket error: %s", std::strerror(static_cast<int>(-n)));  // e.g. ICMP
      const double now = monotonic();
      if (n >= 0)
        onDatagram(buf.data(), static_cast<std::size_t>(n), src, now);
      else
        checkWatchdog(now);
    }
  }

  void onDatagram(const std::uint8_t* data, std::size_t n, const Endpoint& src, double now)
  {
    const ros::Time stamp = ros::Time::now();
    bool resumed = false;
    const Reject r = core_.accept(data, n, src.ip, now, static_cast<std::int64_t>(stamp.toNSec()), last_, resumed);
    if (r != Reject::NONE)
    {
      logReject(r, src, now);
      return;
    }
    if (last_.kind == Accepted::HELLO)
    {
      sendChallenge(src);
      return;
    }
    if (cfg_.publish_tf)
      publishTf(stamp);
    sendCommand(src);
    publishStates(stamp, false);
    if (resumed)
    {
      std::lock_guard<std::mutex> lock(status_mutex_);
      publishStatus(core_.health(now));
    }
  }

  /// One line per reason per second at most (with the number not logged since).
  void logReject(Reject r, const Endpoint& src, double now)
  {
    std::uint64_t suppressed = 0;
    if (!reject_log_.allow(r, now, suppressed))
      return;
    char from[32];
    ROS_ERROR("touchball_receiver: rejected datagram from %s: %s: %s (+%llu more not logged)",
              formatEndpoint(src, from, sizeof from), rejectName(r), rejectHelp(r),
              static_cast<unsigned long long>(suppressed));
  }

  /// Answer a hello: the session nonce for the console's nonce, to the command port.
  void sendChallenge(const Endpoint& src)
  {
    encodeChallenge(++cmd_seq_, wallTime(), last_.session, last_.console_nonce, core_.mac(), challenge_buf_.data());
    const Endpoint dest = commandDestination(src, static_cast<std::uint16_t>(cfg_.command_port));
    char to[32];
    ROS_INFO_THROTTLE(1.0, "touchball_receiver: session opened for the console at %s", formatEndpoint(dest, to, sizeof to));
    if (socket_.sendTo(challenge_buf_.data(), challenge_buf_.size(), dest) != 0)
      core_.countSendError();
  }

  /// Watchdog: STALE status first (consumers hold), then a stale=true state per side.
  void checkWatchdog(double now)
  {
    {
      std::lock_guard<std::mutex> lock(status_mutex_);
      if (!core_.watchdog(now))
        return;
      publishStatus(core_.health(now));
    }
    publishStates(ros::Time::now(), true);
  }

  void publishTf(const ros::Time& stamp)
  {
    const boost::shared_ptr<tf2_msgs::TFMessage> m = tf_->next();
    for (int i = 0; i < kDevices; ++i)
    {
      geometry_msgs::TransformStamped& t = m->transforms[i];
      const DeviceState& d = last_.packet.devices[i];
      t.header.stamp = stamp;
      t.transform.translation.x = d.position[0];
      t.transform.translation.y = d.position[1];
      t.transform.translation.z = d.position[2];
      t.transform.rotation.x = d.orientation[0];
      t.transform.rotation.y = d.orientation[1];
      t.transform.rotation.z = d.orientation[2];
      t.transform.rotation.w = d.orientation[3];
    }
    pub_tf_all_.publish(m);
    if (stamp < next_tf_)
      return;
    pub_tf_.publish(m);
    // next /tf one period later (no catch-up burst after a gap); period 0 (tf_rate 0): every packet
    next_tf_ += tf_period_;
    if (next_tf_ <= stamp)
      next_tf_ = stamp + tf_period_;
  }

  void sendCommand(const Endpoint& src)
  {
    encodeCommand(++cmd_seq_, wallTime(), last_.session, last_.commands, core_.mac(), cmd_buf_.data());
    const Endpoint dest = commandDestination(src, static_cast<std::uint16_t>(cfg_.command_port));
    const int err = socket_.sendTo(cmd_buf_.data(), cmd_buf_.size(), dest);
    if (err != 0)
    {
      core_.countSendError();
      char to[32];
      ROS_ERROR_THROTTLE(1.0, "touchball_receiver: cannot send command to %s: %s", formatEndpoint(dest, to, sizeof to),
                         std::strerror(err));
    }
  }

  /// Per-side topics from last_ (stale: only the state, stale = true, zero twist).
  void publishStates(const ros::Time& stamp, bool stale)
  {
    for (int i = 0; i < kDevices; ++i)
    {
      Side& s = sides_[i];
      const DeviceState& d = last_.packet.devices[i];
      const boost::shared_ptr<saras_msgs::HapticDeviceState> st = s.state->next();
      st->header.stamp = stamp;
      st->pose.position.x = d.position[0];
      st->pose.position.y = d.position[1];
      st->pose.position.z = d.position[2];
      st->pose.orientation.x = d.orientation[0];
      st->pose.orientation.y = d.orientation[1];
      st->pose.orientation.z = d.orientation[2];
      st->pose.orientation.w = d.orientation[3];
      const double* v = last_.linear[i];
      const double* w = last_.angular[i];
      st->twist.linear.x = stale ? 0.0 : v[0];
      st->twist.linear.y = stale ? 0.0 : v[1];
      st->twist.linear.z = stale ? 0.0 : v[2];
      st->twist.angular.x = stale ? 0.0 : w[0];
      st->twist.angular.y = stale ? 0.0 : w[1];
      st->twist.angular.z = stale ? 0.0 : w[2];
      st->clip_angle = d.clip_angle;
      st->clutch = d.clutch();
      st->clip_button = d.clipButton();
      st->packet_seq = last_.packet.seq;
      st->sender_time = last_.packet.sender_time;
      st->stale = stale;
      s.pub_state.publish(st);
      if (!stale)
        publishDerived(s, *st, d);
    }
  }

  /// pose, twist and (when they changed) buttons of one side, copied from its state message.
  static void publishDerived(Side& s, const saras_msgs::HapticDeviceState& st, const DeviceState& d)
  {
    const boost::shared_ptr<geometry_msgs::PoseStamped> pose = s.pose->next();
    pose->header.stamp = st.header.stamp;
    pose->pose = st.pose;
    s.pub_pose.publish(pose);
    const boost::shared_ptr<geometry_msgs::TwistStamped> twist = s.twist->next();
    twist->header.stamp = st.header.stamp;
    twist->twist = st.twist;
    s.pub_twist.publish(twist);
    if (static_cast<std::int64_t>(d.buttons) == s.buttons)
      return;
    s.buttons = static_cast<std::int64_t>(d.buttons);
    const boost::shared_ptr<sensor_msgs::Joy> joy = s.joy->next();
    joy->header.stamp = st.header.stamp;
    joy->axes[0] = static_cast<float>(d.clip_angle);
    joy->buttons[0] = d.clutch() ? 1 : 0;
    joy->buttons[1] = d.clipButton() ? 1 : 0;
    s.pub_buttons.publish(joy);
  }

  /// touchball/status from a health snapshot (caller holds status_mutex_; OK/STALE changes only on
  /// the receive thread, not per packet).
  void publishStatus(const LinkHealth& h)
  {
    saras_msgs::ComponentStatus m;
    m.header.stamp = ros::Time::now();
    m.component = "touchball_receiver";
    m.level = h.level == LinkLevel::STALE ? saras_msgs::ComponentStatus::STALE : saras_msgs::ComponentStatus::OK;
    char text[160];
    m.message = formatStatusText(h, source_, text, sizeof text);
    m.input_age = h.input_age;
    m.received = h.received;
    m.rejected = h.rejectedDatagrams() + h.wrench_rejected;
    pub_status_.publish(m);
  }

  // ------------------------------------------------------------------ timers (callback queue)
  /// Periodic touchball/status and /diagnostics (at once on an OK/STALE change). The receive thread
  /// owns the STALE decision; if that thread itself is stuck (no packet handled for kStuckFactor x
  /// timeout while streaming) the health reports STALE.
  void onStatusTimer(const ros::SteadyTimerEvent&)
  {
    LinkLevel level;
    {
      std::lock_guard<std::mutex> lock(status_mutex_);
      const LinkHealth h = core_.health(monotonic());
      level = h.level;
      publishStatus(h);
    }
    if (level != diagnosed_level_)
      updater_.force_update();
    else
      updater_.update();
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat)
  {
    const double now = monotonic();
    const LinkHealth h = core_.health(now);
    const HealthReport r = describeHealth(h, rate_.update(h.received, now), source_);
    diagnosed_level_ = r.level;
    stat.summary(static_cast<unsigned char>(r.level), r.message);
    for (const auto& kv : r.values)
      stat.add(kv.first, kv.second);
  }

  /// touch_<side>/joint_states for rviz, decimated to ~joint_states_rate (only when a new packet came).
  void onJointTimer(const ros::SteadyTimerEvent&)
  {
    StatePacket p;
    std::int64_t stamp_ns = 0;
    if (!core_.packetSince(js_seen_, p, stamp_ns))
      return;
    ros::Time stamp;
    stamp.fromNSec(static_cast<std::uint64_t>(stamp_ns));
    std::array<double, 6> q;
    for (int i = 0; i < kDevices; ++i)
    {
      if (!touchIk(geometry_, p.devices[i].position, p.devices[i].orientation, q))
        ROS_WARN_THROTTLE(5.0, "touchball_receiver: %s handle pose outside the Touch workspace (joint_states clamped)",
                          kDeviceNames[i]);
      Side& s = sides_[i];
      s.js.header.stamp = stamp;
      std::copy(q.begin(), q.end(), s.js.position.begin());
      s.pub_js.publish(s.js);
    }
  }

  const ReceiverConfig cfg_;
  ReceiverCore core_;
  UdpSocket socket_;
  diagnostic_updater::Updater updater_;
  char source_[64] = {};  ///< accepted console "<ip>:<port>" ("*" = any) for the status texts
  std::mutex status_mutex_;
  std::array<std::string, kDevices> frames_;
  saras_common::InlineCallbackQueue wrench_queue_;  ///< wrench_cmd callbacks (declared before sides_: outlives them)
  std::array<Side, kDevices> sides_;
  std::unique_ptr<saras_common::MessagePool<tf2_msgs::TFMessage>> tf_;
  ros::Publisher pub_tf_, pub_tf_all_, pub_status_;
  ros::Time next_tf_;     ///< receive thread: stamp from which the next stylus TF goes to /tf
  ros::Duration tf_period_;  ///< 1 / ~tf_rate (0: every packet), set at start-up
  ros::SteadyTimer status_timer_, js_timer_;
  // receive thread only:
  std::thread thread_;
  std::atomic<bool> running_{ false };
  AcceptedPacket last_;
  std::array<std::uint8_t, kCommandSize> cmd_buf_{};
  std::array<std::uint8_t, kChallengeSize> challenge_buf_{};
  RejectLogLimiter reject_log_;
  std::uint32_t cmd_seq_ = 0;
  // callback queue only:
  LinkLevel diagnosed_level_ = LinkLevel::STALE;
  RateMeter rate_;
  TouchGeometry geometry_;
  std::uint64_t js_seen_ = 0;
};

/// Nodelet `saras_drivers/TouchballReceiver` (nodelet_plugins.xml); as a node:
/// `rosrun nodelet nodelet standalone saras_drivers/TouchballReceiver`.
class TouchballReceiverNodelet : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    try
    {
      // topics in the nodelet's own namespace (/touchball/...), not /teleop/ of the manager
      receiver_.reset(new TouchballReceiver(getNodeHandle(), getPrivateNodeHandle(), saras_common::nodeletNamespace(getName()),
                                            getName()));
    }
    catch (const std::exception& e)
    {
      ROS_FATAL("%s: %s", getName().c_str(), e.what());
      throw;
    }
  }
  std::unique_ptr<TouchballReceiver> receiver_;
};

}  // namespace touchball
}  // namespace saras_drivers

PLUGINLIB_EXPORT_CLASS(saras_drivers::touchball::TouchballReceiverNodelet, nodelet::Nodelet)
