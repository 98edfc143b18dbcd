/**
 * tank_master / tank_slave nodelets (saras_teleop/TankMaster, saras_teleop/TankSlave): the energy
 * tanks of the passivity layer (see tank_node.h). Executables tank_master and tank_slave.
 */
#include <pluginlib/class_list_macros.hpp>

#include "tank_node.h"

namespace saras_teleop
{
namespace node
{
/// Nodelet `saras_teleop/TankMaster`: master tank (wrench actions on the Touch devices).
class TankMasterNodelet : public NodeletAdapter<TankNode<MasterTraits>>
{
};

/// Nodelet `saras_teleop/TankSlave`: slave tank (twist actions on the SARAS arms).
class TankSlaveNodelet : public NodeletAdapter<TankNode<SlaveTraits>>
{
};

}  // namespace node
}  // namespace saras_teleop

PLUGINLIB_EXPORT_CLASS(saras_teleop::node::TankMasterNodelet, nodelet::Nodelet)
PLUGINLIB_EXPORT_CLASS(saras_teleop::node::TankSlaveNodelet, nodelet::Nodelet)
