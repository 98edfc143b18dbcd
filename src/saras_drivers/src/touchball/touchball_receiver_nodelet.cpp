/**
 * @file touchball_receiver_nodelet.cpp
 * @brief Nodelet saras_drivers/TouchballReceiver: ROS side of the Touchball console link (UDP).
 *
 * Listens on ~bind_address:~port for state packets (docs/touchball_protocol.md) from
 * ~allowed_source. A socket thread waits in ppoll() for a datagram or the watchdog deadline (no
 * busy loop) and publishes every accepted packet at once, from preallocated pooled messages
 * (boost::shared_ptr: zero-copy to nodelets in the same manager, e.g. the teleoperation's
 * tf_transformer), in this order (the teleoperation path first):
 *
 *   /tf                       touch_<side>/base -> touch_<side>/stylus, both sides in one TFMessage
 *   touchball/<side>/state    saras_msgs/HapticDeviceState (frame touch_<side>/base)
 *   touchball/<side>/pose     geometry_msgs/PoseStamped
 *   touchball/<side>/twist    geometry_msgs/TwistStamped   [m/s, rad/s] in touch_<side>/base
 *   touchball/<side>/buttons  sensor_msgs/Joy               buttons [clutch, clip], axes [clip angle rad]
 *
 * and answers each accepted packet with a command packet (sent before the non-TF topics) carrying
 * the latest touchball/<side>/wrench_cmd (geometry_msgs/WrenchStamped in touch_<side>/base, TCP_NODELAY;
 * older than ~wrench_timeout, NaN or another frame => zero force). Timers: touch_<side>/joint_states
 * (sensor_msgs/JointState, rviz) at ~joint_states_rate; touchball/status (saras_msgs/ComponentStatus) at
 * ~status_rate plus immediately on change; the /saras/status heartbeat (1 Hz + on change) comes from the
 * socket thread. Watchdog: no valid packet for ~timeout => STALE status first (consumers hold), then one
 * stale state per side, published by the socket thread at the deadline itself. Header stamps are the
 * receive time (ros::Time::now()). Parameters: config/touchball.yaml (units there); an invalid value is
 * a fatal start-up error naming the parameter.
 */
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <boost/make_shared.hpp>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <saras_msgs/ComponentStatus.h>
#include <saras_msgs/HapticDeviceState.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/Joy.h>
#include <tf2_msgs/TFMessage.h>

#include "saras_drivers/touchball_kinematics.h"
#include "saras_drivers/touchball_link.h"
#include "saras_drivers/nodelet_namespace.h"

namespace saras_drivers
{
namespace touchball
{
namespace
{
constexpr std::size_t kRecvBuffer = 2048;  ///< [bytes] > any packet: oversized datagrams stay detectable
constexpr double kIdleWake = 0.1;          ///< [s] socket-thread wake-up while STALE (heartbeat, shutdown)
constexpr double kStuckFactor = 3.0;       ///< status timer reports STALE if no packet was handled for this x timeout
constexpr double kHeartbeatPeriod = 1.0;   ///< [s] /saras/status
constexpr std::size_t kPoolSize = 16;      ///< messages per topic ring (> in-process subscriber backlog)

double monotonic()
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double wallTime()
{
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/**
 * Ring of preallocated shared messages: next() returns one that nobody else references any more
 * (an in-process subscriber's queue may still hold the previous ones), so it can be overwritten and
 * published zero-copy without allocating. Only if every slot is still held is a new message made
 * (counted in allocations()).
 */
template <class M>
class SharedRing
{
public:
  explicit SharedRing(const M& prototype) : prototype_(prototype)
  {
    for (auto& s : slots_)
      s = boost::make_shared<M>(prototype);
  }
  boost::shared_ptr<M> next()
  {
    for (std::size_t k = 0; k < kPoolSize; ++k)
    {
      cursor_ = (cursor_ + 1) % kPoolSize;
      if (slots_[cursor_].unique())
        return slots_[cursor_];
    }
    ++allocations_;
    return slots_[cursor_] = boost::make_shared<M>(prototype_);
  }
  std::uint64_t allocations() const { return allocations_; }

private:
  M prototype_;
  std::array<boost::shared_ptr<M>, kPoolSize> slots_;
  std::size_t cursor_ = 0;
  std::uint64_t allocations_ = 0;
};

// ------------------------------------------------------------------ validated parameters
[[noreturn]] void invalid(const ros::NodeHandle& pnh, const std::string& name, const std::string& value,
                          const std::string& rule)
{
  throw std::invalid_argument("parameter " + pnh.resolveName(name) + " = " + value + " is invalid: " + rule);
}

double paramNumber(const ros::NodeHandle& pnh, const std::string& name, double def, bool strictly_positive,
                   const std::string& unit, const std::string& doc)
{
  double v = def;
  XmlRpc::XmlRpcValue x;
  if (pnh.getParam(name, x))
  {
    if (x.getType() == XmlRpc::XmlRpcValue::TypeInt)
      v = static_cast<int>(x);
    else if (x.getType() == XmlRpc::XmlRpcValue::TypeDouble)
      v = static_cast<double>(x);
    else
      invalid(pnh, name, x.toXml(), doc + " (a number) [" + unit + "]");
  }
  if (!std::isfinite(v) || (strictly_positive ? !(v > 0.0) : !(v >= 0.0)))
    invalid(pnh, name, std::to_string(v), doc + (strictly_positive ? " (> 0)" : " (>= 0)") + " [" + unit + "]");
  return v;
}

int paramInt(const ros::NodeHandle& pnh, const std::string& name, int def, int lo, int hi, const std::string& doc)
{
  XmlRpc::XmlRpcValue x;
  if (!pnh.getParam(name, x))
    return def;
  if (x.getType() != XmlRpc::XmlRpcValue::TypeInt)
    invalid(pnh, name, x.toXml(), doc + " (an integer)");
  const int v = static_cast<int>(x);
  if (v < lo || v > hi)
    invalid(pnh, name, std::to_string(v), doc + " (" + std::to_string(lo) + ".." + std::to_string(hi) + ")");
  return v;
}

std::string paramText(const ros::NodeHandle& pnh, const std::string& name, const std::string& def,
                      const std::string& doc)
{
  XmlRpc::XmlRpcValue x;
  if (!pnh.getParam(name, x))
    return def;
  if (x.getType() != XmlRpc::XmlRpcValue::TypeString)
    invalid(pnh, name, x.toXml(), doc + " (a string)");
  return static_cast<std::string>(x);
}

bool paramBool(const ros::NodeHandle& pnh, const std::string& name, bool def, const std::string& doc)
{
  XmlRpc::XmlRpcValue x;
  if (!pnh.getParam(name, x))
    return def;
  if (x.getType() != XmlRpc::XmlRpcValue::TypeBoolean)
    invalid(pnh, name, x.toXml(), doc + " (true or false)");
  return static_cast<bool>(x);
}

/// IPv4 address of a parameter (host byte order).
std::uint32_t paramAddress(const ros::NodeHandle& pnh, const std::string& name, const std::string& text,
                           const std::string& doc)
{
  in_addr a{};
  if (inet_pton(AF_INET, text.c_str(), &a) != 1)
    invalid(pnh, name, "'" + text + "'", doc + " (an IPv4 address)");
  return ntohl(a.s_addr);
}
}  // namespace

/// Parameters of the receiver (config/touchball.yaml); units in brackets.
struct ReceiverConfig
{
  std::string bind_address = "127.0.0.1";  ///< local IPv4 address to listen on (0.0.0.0 = all)
  int port = 5005;                         ///< UDP port of the state stream
  std::string allowed_source = "127.0.0.1";  ///< console IPv4 address; '' or '*' = any
  int command_port = 5006;                 ///< console UDP port for force commands; 0 = source port
  LinkParams link;                         ///< timeout [s], resync_after [s], twist_cutoff_hz [Hz]
  double max_force = 3.3;                  ///< [N] force command clamp
  double max_torque = 0.0;                 ///< [N m] torque command clamp
  double wrench_timeout = 0.1;             ///< [s] age after which a force command is dropped
  double status_rate = 10.0;               ///< [Hz] touchball/status
  double joint_states_rate = 100.0;        ///< [Hz] touch_<side>/joint_states (0 = off)
  bool publish_tf = true;                  ///< broadcast touch_<side>/base -> stylus
  int publish_queue_size = 0;              ///< outgoing queue per subscriber of the per-packet topics (0 = 100)
  int realtime_priority = 10;              ///< SCHED_FIFO priority of the socket thread (0 = normal)

  explicit ReceiverConfig(const ros::NodeHandle& pnh)
  {
    bind_address = paramText(pnh, "bind_address", bind_address, "local IP address to listen on (0.0.0.0 = all)");
    paramAddress(pnh, "bind_address", bind_address, "local IP address to listen on");
    port = paramInt(pnh, "port", port, 0, 65535, "UDP port of the state stream");
    allowed_source = paramText(pnh, "allowed_source", allowed_source, "console IP address; '' or '*' = any");
    link.any_source = allowed_source.empty() || allowed_source == "*";
    if (!link.any_source)
      link.source_ip = paramAddress(pnh, "allowed_source", allowed_source, "console IP address, '' or '*' = any");
    command_port = paramInt(pnh, "command_port", command_port, 0, 65535, "console UDP port for force commands");
    link.timeout = paramNumber(pnh, "timeout", 0.03, true, "s", "watchdog timeout");
    link.resync_after = paramNumber(pnh, "resync_after", 1.0, true, "s", "silence after which the sequence restarts");
    if (link.resync_after < link.timeout)
      invalid(pnh, "resync_after", std::to_string(link.resync_after), "must be >= ~timeout [s]");
    link.twist_cutoff_hz = paramNumber(pnh, "twist_cutoff_hz", 100.0, false, "Hz", "twist low-pass cut-off (0 = none)");
    max_force = paramNumber(pnh, "max_force", max_force, false, "N", "force command clamp");
    max_torque = paramNumber(pnh, "max_torque", max_torque, false, "N m", "torque command clamp");
    wrench_timeout = paramNumber(pnh, "wrench_timeout", wrench_timeout, true, "s", "age after which a force command is dropped");
    status_rate = paramNumber(pnh, "status_rate", status_rate, true, "Hz", "touchball/status rate");
    joint_states_rate = paramNumber(pnh, "joint_states_rate", joint_states_rate, false, "Hz",
                                    "touch_<side>/joint_states rate (0 = off)");
    publish_tf = paramBool(pnh, "publish_tf", publish_tf, "broadcast touch_<side>/base -> stylus");
    publish_queue_size = paramInt(pnh, "publish_queue_size", publish_queue_size, 0, 100000,
                                  "outgoing queue of the per-packet topics (0 = 100)");
    realtime_priority = paramInt(pnh, "realtime_priority", realtime_priority, 0, 99,
                                 "SCHED_FIFO priority 1-99 of the socket thread (0 = normal scheduling)");
  }
};

/**
 * One Touchball console link: socket, socket thread, publishers, timers. Threads: the socket thread
 * (decode, publish, command, watchdog, heartbeat) and the nodelet's callback queue (wrench_cmd
 * subscriptions, status and joint_states timers); shared state is guarded by mutex_ (link, latches)
 * and status_mutex_ (orders the STALE/OK decisions with the periodic touchball/status).
 */
class TouchballReceiver
{
public:
  /// @param ns namespace of the node (absolute, ending in '/'): the topics are <ns>touchball/...
  TouchballReceiver(ros::NodeHandle& nh, ros::NodeHandle& pnh, const std::string& ns)
    : cfg_(pnh)
    , link_(cfg_.link)
    , latches_{ { WrenchLatch(cfg_.max_force, cfg_.max_torque, cfg_.wrench_timeout),
                  WrenchLatch(cfg_.max_force, cfg_.max_torque, cfg_.wrench_timeout) } }
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
      s.pub_buttons = nh.advertise<sensor_msgs::Joy>(tns + "buttons", qs);
      saras_msgs::HapticDeviceState st;
      st.header.frame_id = frames_[i];
      st.device = side;
      st.pose.orientation.w = 1.0;
      st.stale = true;
      s.state.reset(new SharedRing<saras_msgs::HapticDeviceState>(st));
      geometry_msgs::PoseStamped pose;
      pose.header.frame_id = frames_[i];
      s.pose.reset(new SharedRing<geometry_msgs::PoseStamped>(pose));
      geometry_msgs::TwistStamped twist;
      twist.header.frame_id = frames_[i];
      s.twist.reset(new SharedRing<geometry_msgs::TwistStamped>(twist));
      sensor_msgs::Joy joy;
      joy.header.frame_id = frames_[i];
      joy.axes.assign(1, 0.0f);
      joy.buttons.assign(2, 0);
      s.joy.reset(new SharedRing<sensor_msgs::Joy>(joy));
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
      s.sub_wrench = nh.subscribe<geometry_msgs::WrenchStamped>(
          tns + "wrench_cmd", 10, [this, i](const geometry_msgs::WrenchStamped::ConstPtr& m) { onWrench(i, *m); },
          ros::VoidConstPtr(), fast);
    }
    tf_.reset(new SharedRing<tf2_msgs::TFMessage>(tf));
    if (cfg_.publish_tf)
      pub_tf_ = nh.advertise<tf2_msgs::TFMessage>("/tf", qs);
    pub_status_ = nh.advertise<saras_msgs::ComponentStatus>(ns + "touchball/status", 10);
    pub_heartbeat_ = nh.advertise<saras_msgs::ComponentStatus>("/saras/status", 10);

    openSocket();
    status_timer_ = nh.createSteadyTimer(ros::WallDuration(1.0 / cfg_.status_rate), &TouchballReceiver::onStatusTimer, this);
    if (cfg_.joint_states_rate > 0.0)
      js_timer_ = nh.createSteadyTimer(ros::WallDuration(1.0 / cfg_.joint_states_rate),
                                       &TouchballReceiver::onJointTimer, this);
    ROS_INFO("touchball_receiver: listening on %s:%d, accepting %s, watchdog %.0f ms", cfg_.bind_address.c_str(),
             cfg_.port, cfg_.link.any_source ? "any source" : cfg_.allowed_source.c_str(), 1e3 * cfg_.link.timeout);
    running_ = true;
    thread_ = std::thread(&TouchballReceiver::run, this);
  }

  ~TouchballReceiver()
  {
    running_ = false;
    if (thread_.joinable())
      thread_.join();  // wakes within kIdleWake or the watchdog deadline
    if (fd_ >= 0)
      ::close(fd_);
  }

private:
  struct Side
  {
    ros::Publisher pub_state, pub_pose, pub_twist, pub_buttons, pub_js;
    ros::Subscriber sub_wrench;
    std::unique_ptr<SharedRing<saras_msgs::HapticDeviceState>> state;
    std::unique_ptr<SharedRing<geometry_msgs::PoseStamped>> pose;
    std::unique_ptr<SharedRing<geometry_msgs::TwistStamped>> twist;
    std::unique_ptr<SharedRing<sensor_msgs::Joy>> joy;
    sensor_msgs::JointState js;  ///< timer thread only
  };

  void openSocket()
  {
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0)
      throw std::runtime_error(std::string("cannot create the UDP socket: ") + std::strerror(errno));
    const int rcvbuf = 1 << 20;
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(cfg_.port));
    inet_pton(AF_INET, cfg_.bind_address.c_str(), &a.sin_addr);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0)
    {
      const std::string err = std::strerror(errno);
      ::close(fd_);
      fd_ = -1;
      throw std::runtime_error("cannot listen on " + cfg_.bind_address + ":" + std::to_string(cfg_.port) + ": " + err);
    }
  }

  // ------------------------------------------------------------------ ROS inputs (callback queue)
  void onWrench(int i, const geometry_msgs::WrenchStamped& m)
  {
    const auto& f = m.wrench.force;
    const auto& t = m.wrench.torque;
    if (m.header.frame_id != frames_[i])
    {
      ++wrench_rejected_;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        latches_[i].clear();
      }
      ROS_ERROR_THROTTLE(1.0, "touchball_receiver: wrench_cmd frame '%s' != '%s', zero force",
                         m.header.frame_id.c_str(), frames_[i].c_str());
      return;
    }
    const double force[3] = { f.x, f.y, f.z }, torque[3] = { t.x, t.y, t.z };
    bool ok;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ok = latches_[i].set(force, torque, monotonic());
    }
    if (!ok)
    {
      ++wrench_rejected_;
      ROS_ERROR_THROTTLE(1.0, "touchball_receiver: non-finite wrench_cmd on %s, zero force", kDeviceNames[i]);
    }
  }

  // ------------------------------------------------------------------ socket thread
  void setRealtime()
  {
    const int prio = cfg_.realtime_priority;
    if (prio <= 0)
      return;
    sched_param sp{};
    sp.sched_priority = prio;
    const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    if (err == 0)
      ROS_INFO("touchball_receiver: socket thread at SCHED_FIFO priority %d", prio);
    else
      ROS_WARN("touchball_receiver: cannot set ~realtime_priority %d (%s): normal scheduling, the watchdog and "
               "latency then depend on the host load (grant CAP_SYS_NICE or an rtprio limit, or set it to 0)",
               prio, std::strerror(err));
  }

  void run()
  {
    pthread_setname_np(pthread_self(), "touchball_rx");  // visible in top -H, /proc/<pid>/task/*/comm
    setRealtime();
    std::array<std::uint8_t, kRecvBuffer> buf;
    pollfd pfd{ fd_, POLLIN, 0 };
    while (running_ && ros::ok())
    {
      double wait;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        wait = link_.waitTime(monotonic(), stale_, kIdleWake);
      }
      bool ready = true;  // deadline passed (thread descheduled): still look at what is queued first
      if (wait > 0.0)
      {
        timespec ts;
        ts.tv_sec = static_cast<time_t>(wait);
        ts.tv_nsec = static_cast<long>((wait - static_cast<double>(ts.tv_sec)) * 1e9);
        const int r = ::ppoll(&pfd, 1, &ts, nullptr);
        ready = r > 0;
        if (r < 0 && errno != EINTR)
          ROS_ERROR_THROTTLE(1.0, "touchball_receiver: poll error: %s", std::strerror(errno));
      }
      ssize_t n = -1;
      sockaddr_in src{};
      if (ready)
      {
        socklen_t len = sizeof src;
        n = ::recvfrom(fd_, buf.data(), buf.size(), MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&src), &len);
        if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
          ROS_ERROR_THROTTLE(1.0, "touchball_receiver: socket error: %s", std::strerror(errno));  // e.g. ICMP
      }
      const double now = monotonic();
      if (n >= 0)
        onDatagram(buf.data(), static_cast<std::size_t>(n), src, now);
      else if (!stale_ && link_.isStale(now))  // link_ is written by this thread only
        declareStale(now);
      if (now - last_heartbeat_ >= kHeartbeatPeriod || heartbeat_changed_)
      {
        heartbeat_changed_ = false;
        last_heartbeat_ = now;
        pub_heartbeat_.publish(statusMessage(now, stale_, false));
      }
    }
  }

  void onDatagram(const std::uint8_t* data, std::size_t n, const sockaddr_in& src, double now)
  {
    const ros::Time stamp = ros::Time::now();
    Reject r;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      r = link_.accept(data, n, ntohl(src.sin_addr.s_addr), now);
      if (r == Reject::NONE)
      {
        packet_ = link_.packet();
        for (int i = 0; i < kDevices; ++i)
        {
          std::copy(link_.twist(i).linear(), link_.twist(i).linear() + 3, linear_[i]);
          std::copy(link_.twist(i).angular(), link_.twist(i).angular() + 3, angular_[i]);
          commands_[i] = latches_[i].get(now);
        }
        receive_stamp_ = stamp;
      }
    }
    if (r != Reject::NONE)
    {
      char ip[INET_ADDRSTRLEN] = "?";
      inet_ntop(AF_INET, &src.sin_addr, ip, sizeof ip);
      ROS_ERROR_THROTTLE(1.0, "touchball_receiver: rejected datagram from %s: %s (%lu rejected so far)", ip,
                         rejectName(r), static_cast<unsigned long>(link_.rejectedTotal()));
      return;
    }
    if (cfg_.publish_tf)
      publishTf(stamp);
    sendCommand(src);
    publishStates(stamp, false);
    if (stale_)
    {
      std::lock_guard<std::mutex> lock(status_mutex_);
      stale_ = false;
      heartbeat_changed_ = true;
      pub_status_.publish(statusMessage(now, false, false));
    }
  }

  void publishTf(const ros::Time& stamp)
  {
    const boost::shared_ptr<tf2_msgs::TFMessage> m = tf_->next();
    for (int i = 0; i < kDevices; ++i)
    {
      geometry_msgs::TransformStamped& t = m->transforms[i];
      const DeviceState& d = packet_.devices[i];
      t.header.stamp = stamp;
      t.transform.translation.x = d.position[0];
      t.transform.translation.y = d.position[1];
      t.transform.translation.z = d.position[2];
      t.transform.rotation.x = d.orientation[0];
      t.transform.rotation.y = d.orientation[1];
      t.transform.rotation.z = d.orientation[2];
      t.transform.rotation.w = d.orientation[3];
    }
    pub_tf_.publish(m);
  }

  void sendCommand(const sockaddr_in& src)
  {
    cmd_seq_ += 1;
    encodeCommand(cmd_seq_, wallTime(), commands_, cmd_buf_.data());
    sockaddr_in dest = src;
    if (cfg_.command_port > 0)
      dest.sin_port = htons(static_cast<std::uint16_t>(cfg_.command_port));
    if (::sendto(fd_, cmd_buf_.data(), cmd_buf_.size(), MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&dest),
                 sizeof dest) < 0)
    {
      char ip[INET_ADDRSTRLEN] = "?";
      inet_ntop(AF_INET, &dest.sin_addr, ip, sizeof ip);
      ROS_ERROR_THROTTLE(1.0, "touchball_receiver: cannot send command to %s:%d: %s", ip, ntohs(dest.sin_port),
                         std::strerror(errno));
    }
  }

  /// Per-side topics from packet_ (stale: only the state, stale = true, zero twist).
  void publishStates(const ros::Time& stamp, bool stale)
  {
    for (int i = 0; i < kDevices; ++i)
    {
      Side& s = sides_[i];
      const DeviceState& d = packet_.devices[i];
      const boost::shared_ptr<saras_msgs::HapticDeviceState> st = s.state->next();
      st->header.stamp = stamp;
      st->pose.position.x = d.position[0];
      st->pose.position.y = d.position[1];
      st->pose.position.z = d.position[2];
      st->pose.orientation.x = d.orientation[0];
      st->pose.orientation.y = d.orientation[1];
      st->pose.orientation.z = d.orientation[2];
      st->pose.orientation.w = d.orientation[3];
      st->twist.linear.x = stale ? 0.0 : linear_[i][0];
      st->twist.linear.y = stale ? 0.0 : linear_[i][1];
      st->twist.linear.z = stale ? 0.0 : linear_[i][2];
      st->twist.angular.x = stale ? 0.0 : angular_[i][0];
      st->twist.angular.y = stale ? 0.0 : angular_[i][1];
      st->twist.angular.z = stale ? 0.0 : angular_[i][2];
      st->clip_angle = d.clip_angle;
      st->clutch = d.clutch();
      st->clip_button = d.clipButton();
      st->packet_seq = packet_.seq;
      st->sender_time = packet_.sender_time;
      st->stale = stale;
      s.pub_state.publish(st);
      if (stale)
        continue;
      const boost::shared_ptr<geometry_msgs::PoseStamped> pose = s.pose->next();
      pose->header.stamp = stamp;
      pose->pose = st->pose;
      s.pub_pose.publish(pose);
      const boost::shared_ptr<geometry_msgs::TwistStamped> twist = s.twist->next();
      twist->header.stamp = stamp;
      twist->twist = st->twist;
      s.pub_twist.publish(twist);
      const boost::shared_ptr<sensor_msgs::Joy> joy = s.joy->next();
      joy->header.stamp = stamp;
      joy->axes[0] = static_cast<float>(d.clip_angle);
      joy->buttons[0] = d.clutch() ? 1 : 0;
      joy->buttons[1] = d.clipButton() ? 1 : 0;
      s.pub_buttons.publish(joy);
    }
  }

  /// Watchdog fired: STALE status first (consumers hold), then a stale=true state per side.
  void declareStale(double now)
  {
    {
      std::lock_guard<std::mutex> lock(status_mutex_);
      stale_ = true;
      heartbeat_changed_ = true;
      pub_status_.publish(statusMessage(now, true, false));
    }
    publishStates(ros::Time::now(), true);
  }

  saras_msgs::ComponentStatus statusMessage(double now, bool stale, bool stalled)
  {
    saras_msgs::ComponentStatus m;
    m.header.stamp = ros::Time::now();
    m.component = "touchball_receiver";
    m.level = stale ? saras_msgs::ComponentStatus::STALE : saras_msgs::ComponentStatus::OK;
    std::lock_guard<std::mutex> lock(mutex_);
    const double age = link_.inputAge(now);
    char text[256];
    if (stalled)
      std::snprintf(text, sizeof text, "socket thread stalled: no packet handled for %.1f ms", 1e3 * age);
    else if (stale)
      std::snprintf(text, sizeof text, "no valid packet from %s:%d for %.1f ms (timeout %.0f ms)",
                    cfg_.link.any_source ? "*" : cfg_.allowed_source.c_str(), cfg_.port, 1e3 * age,
                    1e3 * cfg_.link.timeout);
    else
      std::snprintf(text, sizeof text, "streaming");
    m.message = std::string(text) + "; gaps " + std::to_string(link_.gaps()) + ", rejected {" +
                link_.rejectedSummary() + "}";
    m.input_age = age;
    m.received = link_.received();
    m.rejected = link_.rejectedTotal() + wrench_rejected_;
    return m;
  }

  // ------------------------------------------------------------------ timers (callback queue)
  /// Periodic touchball/status. The socket thread owns the STALE decision; if that thread itself is
  /// stuck (no packet handled for kStuckFactor x timeout while streaming) the timer reports STALE.
  void onStatusTimer(const ros::SteadyTimerEvent&)
  {
    std::lock_guard<std::mutex> lock(status_mutex_);
    const double now = monotonic();
    double age;
    {
      std::lock_guard<std::mutex> l(mutex_);
      age = link_.inputAge(now);
    }
    const bool stalled = !stale_ && age > kStuckFactor * cfg_.link.timeout;
    pub_status_.publish(statusMessage(now, stale_ || stalled, stalled));
  }

  /// touch_<side>/joint_states for rviz, decimated to ~joint_states_rate (only when a new packet came).
  void onJointTimer(const ros::SteadyTimerEvent&)
  {
    StatePacket p;
    ros::Time stamp;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!link_.hasValid() || (js_published_ && link_.packet().seq == js_seq_))
        return;
      p = link_.packet();
      stamp = receive_stamp_;
    }
    js_seq_ = p.seq;
    js_published_ = true;
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

  ReceiverConfig cfg_;
  TouchballLink link_;                            ///< written by the socket thread under mutex_
  std::array<WrenchLatch, kDevices> latches_;     ///< under mutex_
  std::mutex mutex_, status_mutex_;
  std::array<std::string, kDevices> frames_;
  std::array<Side, kDevices> sides_;
  std::unique_ptr<SharedRing<tf2_msgs::TFMessage>> tf_;
  ros::Publisher pub_tf_, pub_status_, pub_heartbeat_;
  ros::SteadyTimer status_timer_, js_timer_;
  TouchGeometry geometry_;
  // socket thread only:
  int fd_ = -1;
  std::thread thread_;
  std::atomic<bool> running_{ false };
  std::atomic<bool> stale_{ true };
  bool heartbeat_changed_ = true;
  double last_heartbeat_ = -1e9;
  StatePacket packet_;
  double linear_[kDevices][3] = {}, angular_[kDevices][3] = {};
  std::array<DeviceCommand, kDevices> commands_;
  std::array<std::uint8_t, kCommandSize> cmd_buf_{};
  std::uint32_t cmd_seq_ = 0;
  ros::Time receive_stamp_;  ///< under mutex_
  std::atomic<std::uint64_t> wrench_rejected_{ 0 };
  // joint_states timer only:
  std::uint32_t js_seq_ = 0;
  bool js_published_ = false;
};

/// Nodelet `saras_drivers/TouchballReceiver` (nodelet_plugins.xml); executable touchball_receiver loads it.
class TouchballReceiverNodelet : public nodelet::Nodelet
{
private:
  void onInit() override
  {
    try
    {
      // topics in the nodelet's own namespace (/touchball/...), not /teleop/ of the manager
      receiver_.reset(new TouchballReceiver(getNodeHandle(), getPrivateNodeHandle(), nodeletNamespace(getName())));
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
