// mvtm — opening a video for reading (OpenCV's videoio with its FFmpeg backend).
//
// FFmpeg's own log lines ("moov atom not found", decoder warnings) would break the one-line
// error contract of every tool, so they are silenced (OPENCV_FFMPEG_LOGLEVEL=-8, read by OpenCV
// once, at its first capture; a user's own setting wins).
#pragma once

#include <memory>
#include <opencv2/videoio.hpp>
#include <string>

namespace mvtm {

// The open capture; Error naming `path` when FFmpeg cannot open it.
std::unique_ptr<cv::VideoCapture> OpenVideo(const std::string& path);

}  // namespace mvtm
