// tank_slave: energy tank of the slave side (twist actions on the SARAS arms).
#include "tank_node.h"

int main(int argc, char** argv)
{
  return saras_teleop::node::runNode<saras_teleop::node::TankNode<saras_teleop::node::SlaveTraits>>(argc, argv,
                                                                                                      "tank_slave");
}
