#include "saras_visual_feedback/jpeg_encoder.h"

#include <algorithm>
#include <csetjmp>
#include <cstdio>  // jpeglib.h needs FILE
#include <stdexcept>

#include <jpeglib.h>

namespace saras_visual_feedback
{
namespace
{
/// libjpeg error handler: longjmp back to encode() instead of exit().
struct ErrorManager
{
  jpeg_error_mgr pub;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void errorExit(j_common_ptr c)
{
  ErrorManager* e = reinterpret_cast<ErrorManager*>(c->err);
  (*c->err->format_message)(c, e->message);
  std::longjmp(e->jump, 1);
}

void silentMessage(j_common_ptr /*c*/)
{
}

/// Destination writing into a std::vector, growing it (doubling) as needed.
struct VectorDestination
{
  jpeg_destination_mgr pub;
  std::vector<std::uint8_t>* out;
};

constexpr std::size_t kMinBuffer = 64 * 1024;

void initDestination(j_compress_ptr c)
{
  VectorDestination* d = reinterpret_cast<VectorDestination*>(c->dest);
  // the capacity of the previous frame: resized, not reallocated
  d->out->resize(std::max(kMinBuffer, d->out->capacity()));
  d->pub.next_output_byte = d->out->data();
  d->pub.free_in_buffer = d->out->size();
}

boolean emptyOutputBuffer(j_compress_ptr c)
{
  VectorDestination* d = reinterpret_cast<VectorDestination*>(c->dest);
  const std::size_t used = d->out->size();  // libjpeg calls this with the whole buffer full
  d->out->resize(2 * used);
  d->pub.next_output_byte = d->out->data() + used;
  d->pub.free_in_buffer = d->out->size() - used;
  return TRUE;
}

void termDestination(j_compress_ptr c)
{
  VectorDestination* d = reinterpret_cast<VectorDestination*>(c->dest);
  d->out->resize(d->out->size() - d->pub.free_in_buffer);
}
}  // namespace

struct JpegEncoder::State
{
  jpeg_compress_struct cinfo;
  ErrorManager err;
  VectorDestination dest;
};

JpegEncoder::JpegEncoder(int quality) : quality_(quality), state_(new State)
{
  if (quality < 1 || quality > 100)
    throw std::invalid_argument("JPEG quality " + std::to_string(quality) + " outside [1, 100]");
  State& s = *state_;
  s.cinfo.err = jpeg_std_error(&s.err.pub);
  s.err.pub.error_exit = errorExit;
  s.err.pub.output_message = silentMessage;
  jpeg_create_compress(&s.cinfo);  // allocation failure here exits (libjpeg): not recoverable anyway
  s.dest.pub.init_destination = initDestination;
  s.dest.pub.empty_output_buffer = emptyOutputBuffer;
  s.dest.pub.term_destination = termDestination;
  s.cinfo.dest = &s.dest.pub;
}

JpegEncoder::~JpegEncoder()
{
  jpeg_destroy_compress(&state_->cinfo);
}

bool JpegEncoder::encode(const cv::Mat& image, ChannelOrder order, std::vector<std::uint8_t>* out,
                         std::string* error)
{
  J_COLOR_SPACE space;
  switch (image.type())
  {
    case CV_8UC1:
      space = JCS_GRAYSCALE;
      break;
    case CV_8UC3:
      space = order == ChannelOrder::kRgb ? JCS_EXT_RGB : JCS_EXT_BGR;
      break;
    case CV_8UC4:
      space = order == ChannelOrder::kRgb ? JCS_EXT_RGBA : JCS_EXT_BGRA;
      break;
    default:
      *error = "JPEG of an image of type " + std::to_string(image.type()) + " (8-bit 1, 3 or 4 channels only)";
      out->clear();
      return false;
  }
  if (image.empty())
  {
    *error = "JPEG of an empty image";
    out->clear();
    return false;
  }
  State& s = *state_;
  jpeg_compress_struct& c = s.cinfo;
  s.dest.out = out;
  // No C++ object with a destructor lives between here and the libjpeg calls (longjmp target).
  if (setjmp(s.err.jump))
  {
    jpeg_abort_compress(&c);
    *error = std::string("JPEG encoding failed: ") + s.err.message;
    out->clear();
    return false;
  }
  c.image_width = static_cast<JDIMENSION>(image.cols);
  c.image_height = static_cast<JDIMENSION>(image.rows);
  c.input_components = image.channels();
  c.in_color_space = space;
  jpeg_set_defaults(&c);  // YCbCr 4:2:0 (grey: one component), baseline, Huffman tables standard
  jpeg_set_quality(&c, quality_, TRUE);
  jpeg_start_compress(&c, TRUE);
  JSAMPROW rows[16];  // one MCU row of 4:2:0 per call
  while (c.next_scanline < c.image_height)
  {
    const JDIMENSION n = std::min<JDIMENSION>(16, c.image_height - c.next_scanline);
    for (JDIMENSION r = 0; r < n; ++r)
      rows[r] = const_cast<JSAMPROW>(image.ptr<JSAMPLE>(static_cast<int>(c.next_scanline + r)));
    jpeg_write_scanlines(&c, rows, n);
  }
  jpeg_finish_compress(&c);
  return true;
}

}  // namespace saras_visual_feedback
