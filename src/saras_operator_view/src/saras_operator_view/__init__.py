"""Operator view of the SARAS platform: a read-only browser page with the augmented stereo, the
tool distances and their colours, the tank energies and the component health (ROS-free core)."""
