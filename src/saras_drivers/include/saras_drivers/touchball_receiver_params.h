/**
 * @file touchball_receiver_params.h
 * @brief Parameters of the Touchball receiver (config/touchball.yaml), read once and validated
 *        through saras_common::Params. Units in brackets.
 */
#ifndef SARAS_DRIVERS_TOUCHBALL_RECEIVER_PARAMS_H
#define SARAS_DRIVERS_TOUCHBALL_RECEIVER_PARAMS_H

#include <string>

#include <saras_common/params.h>

#include "saras_drivers/touchball_link.h"
#include "saras_drivers/touchball_receiver_core.h"

namespace saras_drivers
{
namespace touchball
{
/// Parameters of the receiver, with their defaults.
struct ReceiverConfig
{
  std::string bind_address = "127.0.0.1";    ///< local IPv4 address to listen on (0.0.0.0 = all)
  int port = 5005;                           ///< UDP port of the state stream
  std::string allowed_source = "127.0.0.1";  ///< console IPv4 address; '' or '*' = any
  int command_port = 5006;                   ///< console UDP port for force commands; 0 = source port
  std::string key_file;                      ///< deployment key (docs/touchball_protocol.md), mode 0600; required
  LinkParams link;                           ///< timeout [s], resync_after [s], twist_cutoff_hz [Hz]; source
  WrenchLimits wrench;                       ///< max_force [N], max_torque [N m], wrench_timeout [s]
  double status_rate = 10.0;                 ///< [Hz] touchball/status
  double joint_states_rate = 100.0;          ///< [Hz] touch_<side>/joint_states (0 = off)
  bool publish_tf = true;                    ///< broadcast touch_<side>/base -> stylus
  double tf_rate = 100.0;                    ///< [Hz] that TF on /tf (0 = every packet); touchball/tf: every packet
  int publish_queue_size = 0;                ///< outgoing queue per subscriber of the per-packet topics (0 = 100)
  int realtime_priority = 10;                ///< SCHED_FIFO priority of the receive thread (0 = normal)
};

/**
 * Read every receiver parameter from @p p (the node's private parameters; absent => default) and
 * derive link.any_source / link.source_ip from allowed_source.
 * @throws saras_common::ParamError naming the parameter, its value, unit and rule
 */
ReceiverConfig readReceiverConfig(const saras_common::Params& p);

}  // namespace touchball
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_TOUCHBALL_RECEIVER_PARAMS_H
