// tank_master: energy tank of the master side (wrench actions on the Touch devices).
#include "tank_node.h"

int main(int argc, char** argv)
{
  return saras_teleop::node::runNode<saras_teleop::node::TankNode<saras_teleop::node::MasterTraits>>(argc, argv,
                                                                                                       "tank_master");
}
