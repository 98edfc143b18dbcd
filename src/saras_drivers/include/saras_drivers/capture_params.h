/**
 * @file capture_params.h
 * @brief Parameters of the stereo capture nodelet (config/stereo_capture.yaml), read once and
 *        validated through saras_common::Params. Units in brackets.
 */
#ifndef SARAS_DRIVERS_CAPTURE_PARAMS_H
#define SARAS_DRIVERS_CAPTURE_PARAMS_H

#include <string>

#include <saras_common/params.h>

#include "saras_drivers/capture_core.h"

namespace saras_drivers
{
namespace capture
{
/// Parameters of the stereo capture, with their defaults; index 0 = left eye, 1 = right eye.
struct CaptureConfig
{
  std::string pipeline[2];          ///< {left,right}_pipeline: V4L2 device, GStreamer pipeline or file; required
  VideoSource source[2];            ///< the pipelines resolved (resolveSource())
  std::string camera_info_url[2];   ///< {left,right}_camera_info_url: file:// or package:// calibration YAML ('' = none)
  std::string camera_name[2] = { "endoscope_left", "endoscope_right" };  ///< {left,right}_camera_name
  std::string frame_id[2] = { "endoscope/left_optical_frame", "endoscope/right_optical_frame" };  ///< {left,right}_frame
  double latency = 0.0;             ///< [s] fixed capture latency subtracted from the grab time
  double pair_tolerance = 0.010;    ///< [s] largest stamp difference of a stereo pair
  int pair_queue = 3;               ///< [frames] frames of one eye waiting for their partner
  double expected_rate = 30.0;      ///< [Hz] nominal frame rate of each eye (diagnostics)
  double rate_tolerance = 0.5;      ///< [-] rates within (1 -+ tolerance) x expected_rate are OK
  double stall_timeout = 2.0;       ///< [s] an open eye without frames this long is an ERROR
  double backoff_min = 0.5;         ///< [s] first delay before reopening a failed source
  double backoff_max = 8.0;         ///< [s] longest delay before reopening
  int max_failed_grabs = 10;        ///< consecutive failed reads before the source is reopened
  double log_period = 5.0;          ///< [s] at most one error line per eye per period
  double diagnostic_period = 1.0;   ///< [s] /diagnostics period
  int image_queue = 2;              ///< [messages] outgoing queue per subscriber of image_raw
  int recorded_queue = 30;          ///< [messages] outgoing queue of camera_info and own /compressed
  int jpeg_quality = 85;            ///< [0-100] own image_raw/compressed (without image_transport's plugin)
};

/**
 * Read every parameter from @p p (the node's private parameters; absent => default).
 * @throws saras_common::ParamError naming the parameter, its value, unit and rule
 */
CaptureConfig readCaptureConfig(const saras_common::Params& p);

}  // namespace capture
}  // namespace saras_drivers

#endif  // SARAS_DRIVERS_CAPTURE_PARAMS_H
