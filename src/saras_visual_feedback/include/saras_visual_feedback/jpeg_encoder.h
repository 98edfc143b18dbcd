/**
 * @file jpeg_encoder.h
 * @brief JPEG encoder for the recorded image streams, on libjpeg-turbo's libjpeg API: encodes
 *        8-bit BGR, RGB, BGRA, RGBA and grey images in their own channel order (libjpeg-turbo's
 *        extended input colour spaces, no colour-conversion copy as cv::imencode makes), baseline
 *        JFIF, 4:2:0 chroma subsampling (cv::imencode's default), straight into the output vector
 *        whose capacity is reused frame after frame.
 *
 * The stream decodes with any JPEG decoder (cv::imdecode, compressed_image_transport) to the
 * same picture cv::imencode gives at the same quality.
 */
#ifndef SARAS_VISUAL_FEEDBACK_JPEG_ENCODER_H
#define SARAS_VISUAL_FEEDBACK_JPEG_ENCODER_H

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "saras_visual_feedback/overlay.h"  // ChannelOrder

namespace saras_visual_feedback
{

/**
 * @brief Reusable JPEG encoder (one per encoding thread: not thread-safe).
 */
class JpegEncoder
{
public:
  /// @param quality [1, 100] libjpeg quality; @throws std::invalid_argument outside
  explicit JpegEncoder(int quality);
  ~JpegEncoder();
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;

  int quality() const { return quality_; }

  /**
   * @brief Encodes @p image (CV_8UC1, CV_8UC3 or CV_8UC4, any step) into @p out (resized to the
   *        stream's length; its capacity is kept for the next frame).
   * @param order channel order of a 3- or 4-channel image
   * @return false (reason in @p error, @p out emptied) for an unsupported image or a libjpeg error
   */
  bool encode(const cv::Mat& image, ChannelOrder order, std::vector<std::uint8_t>* out, std::string* error);

private:
  struct State;
  int quality_;
  std::unique_ptr<State> state_;
};

}  // namespace saras_visual_feedback

#endif  // SARAS_VISUAL_FEEDBACK_JPEG_ENCODER_H
