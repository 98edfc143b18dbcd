// JPEG encoder benchmark for the recorded image streams (run through bench/run; not a test).
//
//   jpeg_bench [iterations] [image file]
//
// Encodes one frame (the image file, else a synthetic 1280x720 tissue-like bgr8 frame) with
// cv::imencode (as compressed_image_transport and the former encoders did: a scalar BGR->RGB
// copy per row inside OpenCV) and with JpegEncoder (libjpeg-turbo, BGR input as is, buffer
// reused), at several qualities. Prints per encode: thread CPU [ms], size [kB] and the PSNR of
// the decoded frame against the original [dB] (the same picture at the same quality: equal PSNR).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "saras_visual_feedback/jpeg_encoder.h"

using saras_visual_feedback::ChannelOrder;
using saras_visual_feedback::JpegEncoder;

namespace
{
double threadCpuMs()
{
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/// Smooth shading, a mid-frequency texture and fine noise, like the rendered tissue.
cv::Mat syntheticFrame(int w, int h)
{
  cv::Mat noise(h / 8, w / 8, CV_32FC3), fine(h, w, CV_32FC3), img(h, w, CV_32FC3);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::NORMAL, 0, 40);
  rng.fill(fine, cv::RNG::NORMAL, 0, 4);
  cv::resize(noise, img, img.size(), 0, 0, cv::INTER_CUBIC);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
    {
      const double r2 = std::pow((x - w / 2.0) / w, 2) + std::pow((y - h / 2.0) / h, 2);
      const float shade = static_cast<float>(1.0 - 1.6 * r2);
      img.at<cv::Vec3f>(y, x) = (img.at<cv::Vec3f>(y, x) + cv::Vec3f(90, 110, 190)) * shade + fine.at<cv::Vec3f>(y, x);
    }
  cv::Mat out;
  img.convertTo(out, CV_8UC3);
  return out;
}

void run(const char* name, int iterations, const cv::Mat& frame, const std::function<bool(std::vector<uchar>*)>& enc)
{
  std::vector<uchar> buf;
  enc(&buf);  // warm up (buffer capacity, tables)
  std::vector<double> ms;
  for (int i = 0; i < iterations; ++i)
  {
    const double t0 = threadCpuMs();
    if (!enc(&buf))
    {
      std::printf("%-40s FAILED\n", name);
      return;
    }
    ms.push_back(threadCpuMs() - t0);
  }
  std::sort(ms.begin(), ms.end());
  double mean = 0;
  for (double m : ms)
    mean += m / ms.size();
  const cv::Mat decoded = cv::imdecode(buf, cv::IMREAD_COLOR);
  std::printf("%-40s %8.3f %8.3f %9.1f %8.2f\n", name, mean, ms[ms.size() / 2], buf.size() / 1024.0,
              cv::PSNR(frame, decoded));
}
}  // namespace

int main(int argc, char** argv)
{
  const int iterations = argc > 1 ? std::max(1, std::atoi(argv[1])) : 200;
  cv::Mat frame = argc > 2 ? cv::imread(argv[2], cv::IMREAD_COLOR) : syntheticFrame(1280, 720);
  if (frame.empty())
  {
    std::fprintf(stderr, "jpeg_bench: cannot read %s\n", argv[2]);
    return 1;
  }
  std::printf("frame %dx%d bgr8 (%s), %d encodes each, thread CPU per encode\n", frame.cols, frame.rows,
              argc > 2 ? argv[2] : "synthetic", iterations);
  std::printf("%-40s %8s %8s %9s %8s\n", "encoder", "mean ms", "p50 ms", "size kB", "PSNR dB");
  for (int q : { 95, 85, 80 })
  {
    const std::vector<int> params{ cv::IMWRITE_JPEG_QUALITY, q };
    run(("cv::imencode q" + std::to_string(q)).c_str(), iterations, frame,
        [&](std::vector<uchar>* b) { return cv::imencode(".jpg", frame, *b, params); });
    JpegEncoder encoder(q);
    std::string error;
    run(("JpegEncoder (libjpeg-turbo BGR) q" + std::to_string(q)).c_str(), iterations, frame,
        [&](std::vector<uchar>* b) { return encoder.encode(frame, ChannelOrder::kBgr, b, &error); });
  }
  return 0;
}
