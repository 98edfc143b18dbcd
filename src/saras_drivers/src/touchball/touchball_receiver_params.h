/**
 * @file touchball_receiver_params.h
 * @brief Reads the receiver's private parameters once (type-checked) into a validated
 *        ReceiverConfig; a bad value is a std::invalid_argument naming the parameter.
 */
#ifndef SARAS_DRIVERS_TOUCHBALL_RECEIVER_PARAMS_H
#define SARAS_DRIVERS_TOUCHBALL_RECEIVER_PARAMS_H

#include <ros/node_handle.h>

#include "saras_drivers/touchball_receiver_config.h"

namespace saras_drivers
{
namespace touchball
{
/// @throws std::invalid_argument "parameter <resolved name> = <value> is invalid: <rule> [<unit>]"
ReceiverConfig readReceiverConfig(const ros::NodeHandle& pnh);

}  // namespace touchball
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_TOUCHBALL_RECEIVER_PARAMS_H
