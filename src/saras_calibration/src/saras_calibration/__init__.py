"""SARAS multi-robot calibration suite (ROS-agnostic core).

Modules:
  hand_eye      eye-on-hand calibration (ECM end effector -> endoscope camera), robust
  registration  three-point frames and least-squares point registration (Kabsch)
  pattern       geometry, rendering and detection of the circular calibration pattern
  stereo        headless stereo intrinsics/extrinsics on top of ROS camera_calibration
  world_frames  reading/writing the platform's static world-frame YAML
  synthetic     synthetic images and poses used by tests, benchmarks and simulators
"""
