// mvtm — COLMAP sparse models: cameras, images, points3D in text (.txt) and binary (.bin).
//
// Format: https://colmap.github.io/format.html (text) and COLMAP's
// src/base/reconstruction.cc (binary: little-endian, uint64 counts, camera model ids).
// Conventions:
//  * Image poses are world-to-camera (QW QX QY QZ TX TY TZ), exactly as COLMAP stores them.
//  * Maps are ordered by id, so writing is deterministic; the text writer reproduces COLMAP
//    3.8's own text output byte for byte (header comments, %.17g numbers), so
//    `colmap model_converter` of our files gives back identical text.
//  * Readers check ids (duplicate ids, images naming a camera that does not exist, tracks naming
//    images or 2-D points that do not exist) and report "FILE:LINE: what"; binary readers report
//    the byte offset instead of a line.
//
// The data types live in scene/reconstruction.h; this file only reads and writes them.
// Thread safety: functions are reentrant.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <istream>
#include <map>
#include <string>
#include <vector>

#include "scene/reconstruction.h"

namespace mvtm {

// Reads DIR/{cameras,images,points3D}.{txt,bin}: binary when all three .bin exist, else text.
// Throws Error.
Reconstruction ReadColmapModel(const std::string& dir);
Reconstruction ReadColmapText(const std::string& dir);
Reconstruction ReadColmapBinary(const std::string& dir);
// The three text files one by one, from streams; `name` is used in "NAME:LINE: what" messages.
// Each checks its own file (fields, numbers, duplicate ids); ReadColmapText(dir) also checks
// that the files agree (cameras named by images, points and images named by tracks).
std::map<uint32_t, Camera> ReadColmapCamerasText(std::istream& in, const std::string& name);
std::map<uint32_t, ImageRecord> ReadColmapImagesText(std::istream& in, const std::string& name);
std::map<uint64_t, Point3D> ReadColmapPoints3DText(std::istream& in, const std::string& name);
// images.txt in file order, without the duplicate-id check: calls each(image, line) with the
// line number of the image's pose line (a trajectory reader keeps the file's order and lines).
void ForEachColmapImageText(std::istream& in, const std::string& name,
                            const std::function<void(ImageRecord&&, long line)>& each);
// Writes the three files atomically (each to a temporary name, then renamed; the renames and the
// removal of the other format's files in DIR are one journalled step, WriteTogetherAtomic). The
// other format's files go: a stale binary model beside a new text one would be the one read
// (ReadColmapModel prefers binary). A kill while the files are written leaves the model that was
// there; a kill between the renames leaves a journal, and the next reader or writer of DIR puts
// the whole new model in place (the readers below, HasColmapModel, IsColmapBinaryModel and
// ColmapModelFiles too, look under LockForReading: interrupted commits finished first, its Errors
// thrown, a live writer's renames waited for).
void WriteColmapText(const Reconstruction& r, const std::string& dir);
void WriteColmapBinary(const Reconstruction& r, const std::string& dir);
// The text files' parts, for a writer that makes a model too large to hold piece by piece: the
// same bytes WriteColmapText writes (streams imbued with the "C" locale, precision 17).
// cameras.txt whole; the images.txt header and one image's two lines; the points3D.txt header
// and one point's line. `observations` counts 2-D points with a 3-D point, `track_sum` the
// points' track elements.
void WriteColmapCamerasText(const std::map<uint32_t, Camera>& cameras, const std::string& file);
void WriteColmapImagesHeader(std::ostream& f, size_t images, size_t observations);
void WriteColmapImageText(std::ostream& f, uint32_t id, const ImageRecord& im);
void WriteColmapPointsHeader(std::ostream& f, size_t points, size_t track_sum);
void WriteColmapPointText(std::ostream& f, uint64_t id, const Point3D& p);
// The image names of the model ReadColmapModel would read, from its images file alone (not
// checked against the other two), in file order (binary: by id), under one LockForReading.
std::vector<std::string> ReadColmapImageNames(const std::string& dir);
// True when DIR's model is read as binary: all three .bin files exist (ReadColmapModel's rule).
bool IsColmapBinaryModel(const std::string& dir);
// True when DIR holds a model (text or binary).
bool HasColmapModel(const std::string& dir);
// The model's file names for a format: {"cameras.bin", "images.bin", "points3D.bin"} or .txt.
std::vector<std::string> ColmapModelFileNames(bool binary);
// The model files that exist in DIR, of both formats (what a derived output depends on).
std::vector<std::string> ColmapModelFiles(const std::string& dir);

}  // namespace mvtm
