#!/usr/bin/env bash
# No mvtm program links the libraries that cost start-up time (issue: "start-up under 20 ms"):
# OpenImageIO (~0.47 s, 260 libraries), OpenVDB, OSMesa/LLVM and OpenCV's codecs. They are opened
# with dlopen when needed (libmvtm_oiio.so, libmvtm_vdb.so, libOSMesa), so those modules must
# exist beside the programs and resolve every symbol. Checked with ldd, independently of the build.
#   no_heavy_links.sh BUILD_DIR
set -u
build=$1
status=0
# Programs whose job is decoding or encoding video link OpenCV's videoio (and its codecs): they
# run once per video, where the start-up cost (tens of ms) is nothing beside the decoding.
# dynmask links OpenCV's ximgproc (graph segmentation), which pulls imgcodecs in: it runs once
# per workspace at ~0.1-0.4 s per image, where tens of ms of start-up are nothing either.
video_tools=" frames calibrate mkvideo dynmask "
for exe in "$build"/bin/*; do
  [ -x "$exe" ] || continue
  case "$video_tools" in *" $(basename "$exe") "*) continue;; esac
  heavy=$(ldd "$exe" | grep -oE 'libOpenImageIO[^ ]*|libopenvdb[^ ]*|libOSMesa[^ ]*|libLLVM[^ ]*|libopencv_(imgcodecs|videoio)[^ ]*' | sort -u | tr '\n' ' ')
  if [ -n "$heavy" ]; then
    echo "$(basename "$exe") links $heavy"
    status=1
  fi
done
for module in libmvtm_oiio.so libmvtm_vdb.so; do
  path=$build/lib/mvtm/$module
  if [ ! -f "$path" ]; then
    echo "missing plugin module $path"
    status=1
  elif ldd -r "$path" 2>&1 | grep -q 'undefined symbol'; then
    echo "$module has undefined symbols:"
    ldd -r "$path" 2>&1 | grep 'undefined symbol' | head -5
    status=1
  fi
done
n=$(ls "$build"/bin | wc -l)
[ "$status" = 0 ] && echo "$n programs link none of OpenImageIO, OpenVDB, OSMesa/LLVM, OpenCV codecs; both plugin modules resolve"
exit $status
