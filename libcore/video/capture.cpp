#include "video/capture.h"

#include <cstdlib>

#include "base/error.h"

namespace mvtm {

std::unique_ptr<cv::VideoCapture> OpenVideo(const std::string& path) {
  setenv("OPENCV_FFMPEG_LOGLEVEL", "-8", 0);
  auto cap = std::make_unique<cv::VideoCapture>(path, cv::CAP_FFMPEG);
  if (!cap->isOpened())
    throw Error(path, 0, "cannot open the video (not a video, or a container FFmpeg cannot read)");
  return cap;
}

}  // namespace mvtm
