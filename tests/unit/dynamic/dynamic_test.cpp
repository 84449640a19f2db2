// libcore/dynamic against a scene whose answer is known by construction: a textured ground plane
// seen by cameras driving forward (depth exact: h·fy / (v − cy)), with a textured "vehicle"
// pasted into the photos at known pixels. The truth mask is the pasted rectangle; nothing in
// EstimateDynamic sees it.
#include "dynamic/dynamic.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "base/error.h"

namespace mvtm {
namespace {

constexpr int kW = 240, kH = 120;
constexpr double kHeight = 1.65;

Camera TestCamera() { return ParseCameraSpec("PINHOLE 240 120 120 120 120 50"); }

double GroundTexture(double x, double z) {
  return 0.45 + 0.12 * std::sin(2.1 * x + 0.4 * z) + 0.1 * std::sin(1.7 * z - 0.9 * x) +
         0.08 * std::sin(5.3 * x) * std::cos(3.1 * z);
}

// The vehicle's paint, windows and lights: 4×4-pixel blocks of hashed grey, 0.15..0.75.
double VehicleTexture(int bx, int by) {
  uint32_t h = static_cast<uint32_t>(bx) * 73856093u ^ static_cast<uint32_t>(by) * 19349663u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return 0.15 + 0.6 * (h % 1000) / 1000.0;
}

struct Box {
  int x0, y0, w, h;  // pixels
};

// Camera at (offset_x, 0, z) looking +z over the ground y = kHeight (camera y down); the vehicle
// box painted in the box's own pixel frame; exposure gain applied to everything.
DynamicView MakeView(double z, const Box* vehicle, double gain = 1.0, double offset_x = 0,
                     bool flat = false) {
  DynamicView v;
  v.camera = TestCamera();
  v.world_to_camera = Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-offset_x, 0, -z));
  v.grey.create(kH, kW, CV_32F);
  v.depth.create(kH, kW, CV_32F);
  const Camera& c = v.camera;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      // 3×3 samples per pixel for the colour (a camera low-passes), the centre ray for depth.
      double g = 0;
      for (int sy = -1; sy <= 1; ++sy)
        for (int sx = -1; sx <= 1; ++sx) {
          const double dx = (x + 0.5 + sx / 3.0 - c.cx()) / c.fx();
          const double dy = (y + 0.5 + sy / 3.0 - c.cy()) / c.fy();
          const double t = kHeight / dy;
          g += dy > 1e-3 ? (flat ? 0.5 : GroundTexture(offset_x + t * dx, z + t)) : 0.8;  // sky
        }
      g /= 9;
      const double dy = (y + 0.5 - c.cy()) / c.fy();
      const float depth =
          dy > 1e-3 ? static_cast<float>(kHeight / dy) : std::numeric_limits<float>::infinity();
      if (vehicle && x >= vehicle->x0 && x < vehicle->x0 + vehicle->w && y >= vehicle->y0 &&
          y < vehicle->y0 + vehicle->h)
        g = VehicleTexture((x - vehicle->x0) / 4, (y - vehicle->y0) / 4);
      v.grey.at<float>(y, x) = static_cast<float>(std::min(1.0, g * gain));
      v.depth.at<float>(y, x) = depth;
    }
  return v;
}

// Share of `box`'s pixels masked, and share of the other pixels.
void Score(const cv::Mat& mask, const Box& box, double& recall, double& false_share) {
  int in = 0, hit = 0, out = 0, fp = 0;
  for (int y = 0; y < mask.rows; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool inside = x >= box.x0 && x < box.x0 + box.w && y >= box.y0 && y < box.y0 + box.h;
      const bool on = mask.at<uint8_t>(y, x) != 0;
      if (inside) {
        ++in, hit += on;
      } else {
        ++out, fp += on;
      }
    }
  if (getenv("DYN_DEBUG")) {
    for (int y = 0; y < mask.rows; y += 4) {
      std::string row;
      for (int x = 0; x < kW; x += 2) row += mask.at<uint8_t>(y, x) ? '#' : '.';
      fprintf(stderr, "%3d %s\n", y, row.c_str());
    }
  }
  recall = double(hit) / in;
  false_share = double(fp) / out;
}

TEST(Dynamic, MovingVehicleFoundGroundLeftAlone) {
  const Box at_t{100, 70, 40, 25};
  const Box a{60, 72, 40, 25}, b{140, 68, 40, 25}, c{20, 75, 40, 25}, d{170, 70, 40, 25};
  const DynamicView t = MakeView(10, &at_t);
  const DynamicView n1 = MakeView(8, &a), n2 = MakeView(12, &b), n3 = MakeView(6, &c),
                    n4 = MakeView(14, &d);
  for (bool flow : {false, true}) {
    DynamicOptions o;
    o.flow = flow;
    const DynamicEvidence e = EstimateDynamic(t, {&n1, &n2, &n3, &n4}, o);
    EXPECT_EQ(e.neighbours, 4);
    double recall, fp;
    Score(MaskFromProbability(e.probability, MaskOptions()), at_t, recall, fp);
    EXPECT_GE(recall, 0.85) << "flow " << flow;  // its top rows move least (far road behind)
    // The neighbours' own vehicles sit on some of the target's ground pixels: the median over
    // four neighbours leaves them out.
    EXPECT_LE(fp, 0.01) << "flow " << flow;
  }
}

TEST(Dynamic, VehicleAtTheCamerasSpeedIsFound) {
  // The same box at the same pixels in every photo: no parallax at all, yet the static depth
  // behind it (the road 6 to 13 m ahead) says its pixels should move by 3 to 30 pixels between
  // photos 2 m apart.
  const Box box{100, 65, 40, 25};
  const DynamicView t = MakeView(10, &box);
  const DynamicView n1 = MakeView(8, &box), n2 = MakeView(12, &box), n3 = MakeView(6, &box),
                    n4 = MakeView(14, &box);
  const DynamicEvidence e = EstimateDynamic(t, {&n1, &n2, &n3, &n4}, DynamicOptions());
  // The road just below the box, 3 to 5 m ahead, was under the box in every earlier photo and is
  // out of view of the later ones: nothing confirms it, and it is masked with the box (known
  // limit). Above the box's lower edge, nothing but the box is masked.
  const cv::Mat m = MaskFromProbability(e.probability, MaskOptions());
  double recall, fp;
  Score(m, box, recall, fp);
  EXPECT_GE(recall, 0.75);  // 0.80: its top rows, with the farthest road behind, match by chance
  Score(m(cv::Rect(0, 0, kW, box.y0 + box.h)).clone(), box, recall, fp);
  EXPECT_LE(fp, 0.01);
}

TEST(Dynamic, VehicleAtTheCamerasSpeedFoundByPhotosFartherAlong) {
  // A slow drive (photos 0.2 m apart, as a 15 Hz dashcam in town): the static depth behind a
  // box keeping its pixels moves it by under 3 pixels between neighbours, within the noise.
  // Photos of the drive 2 and 4 m farther along see the road the box covers in the target below
  // the box's image in theirs (a road point d m ahead is d - 2 m from the first; its lowest row
  // sees 2.8 m ahead), compared at the pixels at least 1.5 times their depth (dynmask's reach):
  // 3 and 6 m.
  const Box box{100, 65, 40, 25};  // static depth 5.0 m (row 89) to 12.8 m (row 65)
  const DynamicView t = MakeView(10, &box);
  const DynamicView n1 = MakeView(9.8, &box), n2 = MakeView(10.2, &box), n3 = MakeView(9.6, &box),
                    n4 = MakeView(10.4, &box);
  DynamicView a1 = MakeView(12, &box), a2 = MakeView(14, &box);
  a1.beyond = 3, a2.beyond = 6;
  const std::vector<const DynamicView*> nbs{&n1, &n2, &n3, &n4};
  double recall, fp;
  const DynamicEvidence near = EstimateDynamic(t, nbs, DynamicOptions());
  Score(MaskFromProbability(near.probability, MaskOptions()), box, recall, fp);
  EXPECT_LE(recall, 0.2);  // the neighbours alone miss it (0.007)
  const DynamicEvidence e = EstimateDynamic(t, nbs, DynamicOptions(), {}, {&a1, &a2});
  EXPECT_EQ(e.ahead, 2);
  const cv::Mat m = MaskFromProbability(e.probability, MaskOptions());
  Score(m, box, recall, fp);
  EXPECT_GE(recall, 0.8);
  Score(m(cv::Rect(0, 0, kW, box.y0 + box.h)).clone(), box, recall, fp);
  EXPECT_LE(fp, 0.01);
  // `beyond`: the first photo ahead sees the target's road from 4.8 m on (its lowest row sees
  // 2.8 m ahead of it); at beyond 8 the pixel at row 82 (6.1 m) is not compared, row 70 (9.7 m)
  // still is.
  DynamicView only = a1;
  only.beyond = 0;
  const DynamicEvidence all = EstimateDynamic(t, nbs, DynamicOptions(), {}, {&only});
  EXPECT_TRUE(std::isfinite(all.ahead_photo.at<float>(82, 120)));
  only.beyond = 8;
  const DynamicEvidence far = EstimateDynamic(t, nbs, DynamicOptions(), {}, {&only});
  EXPECT_TRUE(std::isnan(far.ahead_photo.at<float>(82, 120)));
  EXPECT_TRUE(std::isfinite(far.ahead_photo.at<float>(70, 120)));
  // The same drive without the box: the photos farther along agree with the road.
  const DynamicView s = MakeView(10, nullptr), s1 = MakeView(9.8, nullptr),
                    s2 = MakeView(10.2, nullptr);
  DynamicView b1 = MakeView(12, nullptr), b2 = MakeView(14, nullptr);
  b1.beyond = 3, b2.beyond = 6;
  const DynamicEvidence still = EstimateDynamic(s, {&s1, &s2}, DynamicOptions(), {}, {&b1, &b2});
  EXPECT_EQ(cv::countNonZero(MaskFromProbability(still.probability, MaskOptions())), 0);
}

// A moving vehicle whose top stands against the sky: rows 40-80, the horizon at row 50 (cy), so
// its rows 40-49 have no static depth (the sky behind). Its windscreen, rows 44-59, is one dark
// region, five eighths of it (rows 50-59) with depth.
DynamicView TallVehicleView(double z, int x0) {
  const Box box{x0, 40, 40, 41};
  DynamicView v = MakeView(z, &box);
  for (int y = 44; y < 60; ++y)
    for (int x = x0 + 4; x < x0 + 36; ++x) v.grey.at<float>(y, x) = 0.1f;
  return v;
}

TEST(Dynamic, DepthlessPixelsTakeTheirRegionsProbability) {
  const DynamicView t = TallVehicleView(10, 100);
  const DynamicView n1 = TallVehicleView(8, 60), n2 = TallVehicleView(12, 140),
                    n3 = TallVehicleView(6, 20), n4 = TallVehicleView(14, 170);
  const cv::Rect top(104, 46, 32, 4);  // the windscreen's rows without depth (bar its top edge)
  for (double share : {0.5, 0.8}) {
    DynamicOptions o;
    o.region_depth = share;
    const DynamicEvidence e = EstimateDynamic(t, {&n1, &n2, &n3, &n4}, o);
    const cv::Mat m = MaskFromProbability(e.probability, MaskOptions());
    const double masked = cv::countNonZero(m(top)) / double(top.area());
    if (share < 0.625)
      EXPECT_GE(masked, 0.9) << share;  // 0.625 of the region has depth
    else
      EXPECT_LE(masked, 0.1) << share;
    // The sky beside it stays unmasked (no depth, a region of its own).
    EXPECT_EQ(cv::countNonZero(m(cv::Rect(0, 0, 90, 50))), 0) << share;
    EXPECT_EQ(cv::countNonZero(m(cv::Rect(150, 0, 90, 50))), 0) << share;
  }
}

TEST(Dynamic, PartnerOfAnotherDriveFindsAVehicleParkedInThisDriveOnly) {
  // A second drive of the road, 1.5 m to the left and 0.5 m on: the vehicle the target's drive
  // photographed (at the target's speed, so its own neighbours could not see it move) is not
  // there. No same-drive neighbour at all: the partner alone is the evidence.
  const Box box{100, 65, 40, 25};
  const DynamicView t = MakeView(10, &box);
  const DynamicView other = MakeView(10.5, nullptr, 1.1, -1.5);
  const DynamicEvidence e = EstimateDynamic(t, {}, DynamicOptions(), {&other});
  EXPECT_EQ(e.partners, 1);
  double recall, fp;
  Score(MaskFromProbability(e.probability, MaskOptions()), box, recall, fp);
  EXPECT_GE(recall, 0.85);
  EXPECT_LE(fp, 0.01);
  // A partner that saw the far surfaces compares only the pixels at least `beyond` deep: the
  // box's static depth runs from 198 / 39.5 = 5.0 m (row 89) to 198 / 15.5 = 12.8 m (row 65).
  DynamicView far = other;
  far.beyond = 5.0 - 0.1;  // all of the box: found as before
  const DynamicEvidence all = EstimateDynamic(t, {}, DynamicOptions(), {&far});
  Score(MaskFromProbability(all.probability, MaskOptions()), box, recall, fp);
  EXPECT_GE(recall, 0.85);
  EXPECT_TRUE(std::isnan(all.across.at<float>(100, 120)));  // the road nearer: not compared
  far.beyond = 12.8 + 0.1;  // none of it: no evidence there, the road beyond still compared
  const DynamicEvidence none = EstimateDynamic(t, {}, DynamicOptions(), {&far});
  EXPECT_EQ(none.partners, 1);
  Score(MaskFromProbability(none.probability, MaskOptions()), box, recall, fp);
  EXPECT_LE(recall, 0.05);
  EXPECT_TRUE(std::isnan(none.across.at<float>(80, 120)));
  EXPECT_TRUE(std::isfinite(none.across.at<float>(55, 120)));
}

TEST(Dynamic, AVehicleParkedInThePartnersDriveDoesNotMaskTheRoad) {
  // The reverse case: the partner's drive had a vehicle on the road the target sees bare. Warped
  // through the static depth (the road), the partner shows the vehicle where the target shows
  // road; what the partner saw (its own depth map: the vehicle standing at its foot's depth)
  // hides those road points from it, so they are not evidence.
  const Box box{100, 65, 40, 25};
  const DynamicView t = MakeView(10, nullptr);
  DynamicView other = MakeView(10.5, &box, 1.0, -1.5);
  DynamicOptions o;
  o.flow = false;
  const auto masked = [&] {
    const cv::Mat m =
        MaskFromProbability(EstimateDynamic(t, {}, o, {&other}).probability, MaskOptions());
    return double(cv::countNonZero(m)) / double(m.total());
  };
  const double without = masked();
  other.seen = other.depth.clone();
  const float foot = other.depth.at<float>(box.y0 + box.h - 1, box.x0);
  other.seen(cv::Rect(box.x0, box.y0, box.w, box.h)).setTo(foot);
  const double with = masked();
  EXPECT_GE(without, 0.008);  // the ghost: the partner's vehicle painted on the target's road
  EXPECT_LE(with, 0.001) << "without the partner's depth " << without;
}

// A world-fixed box (a vehicle parked in the target's drive only) seen from a camera `d` m
// farther along: its face at depth `z_face` m in the target's view (pixels `box` there) scales
// by z_face / (z_face - d) about the principal point, its paint with it.
DynamicView ParkedView(double z, double d, const Box& box, double z_face) {
  DynamicView v = MakeView(z + d, nullptr);
  const Camera& c = v.camera;
  const double k = z_face / (z_face - d);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const double bx = (x + 0.5 - c.cx()) / k + c.cx() - box.x0;  // in the target's pixels
      const double by = (y + 0.5 - c.cy()) / k + c.cy() - box.y0;
      if (bx >= 0 && bx < box.w && by >= 0 && by < box.h)
        v.grey.at<float>(y, x) = float(VehicleTexture(int(bx) / 4, int(by) / 4));
    }
  return v;
}

TEST(Dynamic, PhotosFartherAlongVetoTheOtherDrivesTrafficNotThisDrives) {
  // Drive A's lead car keeps its pixels (a box at the camera's speed); drive B saw the road bare.
  // B's photo against A's partner: the car painted on B's road (a ghost: A's own neighbours
  // cannot see it move, so A's first pass does not leave it out). B's own photos 2 and 4 m
  // farther along see that road as it is: with the veto, the ghost goes. A's photo against B's
  // partner: A's own photos farther along see the road the car covers (below the car in theirs):
  // no veto, the car stays. A car parked in A only (world-fixed, its face 8 m ahead): A's photos
  // farther along see it nearer and larger, not the road its pixels warp to: it stays too.
  const Box box{100, 65, 40, 25};  // static depth 5.0 m (row 89) to 12.8 m (row 65)
  const DynamicView b = MakeView(10, nullptr), a = MakeView(10.5, &box, 1.0, -1.5);
  DynamicView b1 = MakeView(12, nullptr), b2 = MakeView(14, nullptr);
  b1.beyond = 3, b2.beyond = 6;
  DynamicOptions off, on;
  off.ahead_veto = 0, on.ahead_veto = 0.5;
  const auto masked = [](const DynamicEvidence& e) {
    const cv::Mat m = MaskFromProbability(e.probability, MaskOptions());
    return double(cv::countNonZero(m)) / double(m.total());
  };
  const double ghost = masked(EstimateDynamic(b, {}, off, {&a}, {&b1, &b2}));
  const double vetoed = masked(EstimateDynamic(b, {}, on, {&a}, {&b1, &b2}));
  EXPECT_GE(ghost, 0.008);  // a third of the box's 1000 pixels of 28800
  EXPECT_LE(vetoed, 0.1 * ghost) << "without the veto " << ghost;
  // Drive A's photo: the lead car found against B's partner, not vetoed.
  const DynamicView t = MakeView(10, &box), other = MakeView(10.5, nullptr, 1.1, -1.5);
  DynamicView a1 = MakeView(12, &box), a2 = MakeView(14, &box);
  a1.beyond = 3, a2.beyond = 6;
  double recall, fp;
  const DynamicEvidence lead = EstimateDynamic(t, {}, on, {&other}, {&a1, &a2});
  Score(MaskFromProbability(lead.probability, MaskOptions()), box, recall, fp);
  EXPECT_GE(recall, 0.85);
  // A car parked in A only, its face 8 m ahead (its pixels' static depth: the road from 5.0 to
  // 12.8 m); A's photos 2 and 4 m farther along, which see it nearer and larger: by their own
  // depth maps it hides the road its pixels warp to, so they do not veto it. (Without those
  // maps its uniform or repeating paint can agree with itself: measured 0.44 of it found.)
  const DynamicView parked = ParkedView(10, 0, box, 8);
  DynamicView p1 = ParkedView(10, 2, box, 8), p2 = ParkedView(10, 4, box, 8);
  p1.beyond = 3, p2.beyond = 6;
  // What they saw (densify's maps): the car's face 6 and 4 m ahead of them, over its pixels.
  for (auto [v, d] : {std::pair<DynamicView*, double>{&p1, 2}, {&p2, 4}}) {
    v->seen = v->depth.clone();
    const double k = 8 / (8 - d);
    const Camera& c = v->camera;
    const cv::Rect r(int(std::floor(c.cx() + (box.x0 - c.cx()) * k)),
                     int(std::floor(c.cy() + (box.y0 - c.cy()) * k)), int(std::ceil(box.w * k)),
                     int(std::ceil(box.h * k)));
    v->seen(r & cv::Rect(0, 0, kW, kH)).setTo(float(8 - d));
  }
  const DynamicEvidence kept = EstimateDynamic(parked, {}, on, {&other}, {&p1, &p2});
  Score(MaskFromProbability(kept.probability, MaskOptions()), box, recall, fp);
  double recall_off;
  Score(MaskFromProbability(EstimateDynamic(parked, {}, off, {&other}).probability, MaskOptions()),
        box, recall_off, fp);
  EXPECT_GE(recall, 0.85) << "without the veto " << recall_off;
  // 0 turns the veto off: the photos farther along are then a cue of their own (no partners).
  EXPECT_EQ(masked(EstimateDynamic(b, {}, off, {}, {&b1, &b2})), 0);
}

TEST(Dynamic, PhotosJustBehindDoNotVetoALeadCarTheySeeInThePlace) {
  // Drive A's last photo: its vetoing photos are the two just behind it (1 and 2 m back, at
  // every pixel). A lead car keeping the camera's pace is in them at the same pixels; its paint
  // is panels of 8 x 8 pixels. Warped through the static depth (the road 5 to 12.8 m ahead,
  // 1 to 6 pixels of motion), a photo behind shows mostly the same panel and agrees, as it would
  // with a road it saw as the target does: without the rule below only 0.42 of the car is found.
  // The photo's own pixel, unwarped, agrees as well: such a photo cannot tell the static point
  // from a car keeping its place, and vetoes nothing there. Drive B's partner saw the road bare:
  // the car is found.
  const Box box{100, 65, 40, 25};
  const auto paint = [&](DynamicView v) {
    for (int y = box.y0; y < box.y0 + box.h; ++y)
      for (int x = box.x0; x < box.x0 + box.w; ++x)
        v.grey.at<float>(y, x) = float(VehicleTexture((x - box.x0) / 8, (y - box.y0) / 8));
    return v;
  };
  const DynamicView t = paint(MakeView(10, nullptr)), other = MakeView(10.5, nullptr, 1.1, -1.5);
  DynamicView a1 = paint(MakeView(9, nullptr));
  const DynamicView a2 = paint(MakeView(8, nullptr));
  a1.grey *= 1.1;  // another exposure: its gain against the target is not 1
  DynamicOptions on;
  on.ahead_veto = 0.5;
  double recall, fp;
  const cv::Mat a1_grey = a1.grey.clone();
  const DynamicEvidence lead = EstimateDynamic(t, {}, on, {&other}, {&a1, &a2});
  Score(MaskFromProbability(lead.probability, MaskOptions()), box, recall, fp);
  EXPECT_GE(recall, 0.85);
  EXPECT_LE(fp, 0.01);
  EXPECT_EQ(cv::norm(a1.grey, a1_grey, cv::NORM_INF), 0);  // the views are not changed
  // Drive B's photo, whose photos behind saw the road bare: where A's partner paints the car on
  // it (the other drive's traffic), the road moved in them and the veto holds.
  const DynamicView b = MakeView(10, nullptr), pa = paint(MakeView(10.5, nullptr, 1.0, -1.5));
  const DynamicView b1 = MakeView(9, nullptr), b2 = MakeView(8, nullptr);
  DynamicOptions off = on;
  off.ahead_veto = 0;
  const auto masked = [&](const DynamicOptions& o) {
    return cv::countNonZero(MaskFromProbability(
        EstimateDynamic(b, {}, o, {&pa}, {&b1, &b2}).probability, MaskOptions()));
  };
  const int ghost = masked(off);
  EXPECT_GE(ghost, 240);  // a quarter of the car
  EXPECT_LE(masked(on), 0.05 * ghost) << "without the veto " << ghost;
}

// `v` with a colour image: its luma in every channel, times `white` (a white balance), and in
// `car`'s pixels tinted blue (0.6, 0.9, 1.6 times the luma) at the road's own luma: a vehicle
// the luma cannot tell from the road it covers.
DynamicView Tinted(DynamicView v, const Box* car, cv::Vec3d white = {1, 1, 1}) {
  v.colour.create(kH, kW, CV_8UC3);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool in =
          car && x >= car->x0 && x < car->x0 + car->w && y >= car->y0 && y < car->y0 + car->h;
      const cv::Vec3d tint = in ? cv::Vec3d(0.6, 0.9, 1.6) : cv::Vec3d(1, 1, 1);
      for (int k = 0; k < 3; ++k)
        v.colour.at<cv::Vec3b>(y, x)[k] =
            cv::saturate_cast<uint8_t>(255 * v.grey.at<float>(y, x) * tint[k] * white[k]);
    }
  return v;
}

TEST(Dynamic, PartnersThatSawTheRoadAsThePhotoDidVetoItsNeighboursFlow) {
  // A vehicle of this drive (moving: at other pixels in the neighbour 1 m behind) and the other
  // drive's photo 1.5 m aside, which saw the road bare. Where the partner agrees with the photo
  // (the road), the neighbour's flow residual is dropped; on the vehicle, which the partner did
  // not see, it is kept as it was, and the vehicle is found with the veto as without it.
  const Box at_t{100, 70, 40, 25}, at_n{60, 72, 40, 25};
  const DynamicView t = MakeView(10, &at_t), n = MakeView(9, &at_n),
                    partner = MakeView(10.5, nullptr, 1.0, -1.5);
  DynamicOptions off, on;
  off.partners_veto = 0;
  const DynamicEvidence e0 = EstimateDynamic(t, {&n}, off, {&partner});
  const DynamicEvidence e1 = EstimateDynamic(t, {&n}, on, {&partner});
  int road = 0, road_vetoed = 0, car = 0, car_kept = 0, unseen = 0, unseen_kept = 0;
  for (int y = 60; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool in_t =
          x >= at_t.x0 && x < at_t.x0 + at_t.w && y >= at_t.y0 && y < at_t.y0 + at_t.h;
      const bool in_n = x >= at_n.x0 - 4 && x < at_n.x0 + at_n.w + 4 && y >= at_n.y0 - 4 &&
                        y < at_n.y0 + at_n.h + 4;  // the neighbour's vehicle covers the road
      const float f0 = e0.flow.at<float>(y, x), f1 = e1.flow.at<float>(y, x);
      if (!std::isfinite(f0)) continue;
      if (std::isnan(e0.across.at<float>(y, x))) {  // no partner saw it: nothing to veto with
        ++unseen;
        unseen_kept += f1 == f0;
        continue;
      }
      if (in_t) {
        ++car;
        car_kept += f1 == f0;
      } else if (!in_n && e0.across.at<float>(y, x) < 0.5 * on.threshold) {
        ++road;
        road_vetoed += std::isnan(f1);
      }
    }
  EXPECT_GE(road, 5000);  // the road the partner saw alike, rows 60 to 119
  EXPECT_EQ(road_vetoed, road);
  EXPECT_EQ(unseen_kept, unseen);  // the image's side the partner 1.5 m aside does not see
  // Only the flow: the neighbours' photometric residual is the same with the veto.
  cv::Mat p0 = e0.photometric.clone(), p1 = e1.photometric.clone();
  cv::patchNaNs(p0, -1);
  cv::patchNaNs(p1, -1);
  EXPECT_EQ(cv::countNonZero(p0 != p1), 0);
  EXPECT_GE(car, 900);  // of the box's 1000 pixels
  // Kept on 878 of them (measured): where a 4-pixel block of the paint has the grey of the road
  // the partner saw, within the threshold, the partner agrees with it by chance.
  EXPECT_GE(car_kept, 0.8 * car) << "of " << car;
  double recall[2], fp[2];
  Score(MaskFromProbability(e0.probability, MaskOptions()), at_t, recall[0], fp[0]);
  Score(MaskFromProbability(e1.probability, MaskOptions()), at_t, recall[1], fp[1]);
  EXPECT_GE(recall[0], 0.85);
  EXPECT_GE(recall[1], 0.85);
  EXPECT_LE(fp[1], fp[0] + 0.001);
  // Without a partner there is nothing to veto with.
  cv::Mat a = EstimateDynamic(t, {&n}, on, {}).flow, b = e0.flow.clone();
  cv::patchNaNs(a, -1);
  cv::patchNaNs(b, -1);
  EXPECT_EQ(cv::countNonZero(a != b), 0);
}

TEST(Dynamic, PartnersVetoTheFlowUnderFTimesTheThresholdBeforeTheAheadVetoDropsTheirResidual) {
  // The rule of --partners-veto F, checked pixel by pixel against the partners' residual made
  // without it: the flow becomes NaN exactly where that residual is under F x --threshold. A photo
  // of the drive 3 m farther along (the ahead veto, on by default) saw the road bare too and drops
  // the partners' residual where it agrees; the partners' veto is applied before that, so the
  // pixels both witnesses saw alike lose their flow as well (the other order would keep it).
  const Box at_t{100, 70, 40, 25}, at_n{60, 72, 40, 25};
  const DynamicView t = MakeView(10, &at_t), n = MakeView(9, &at_n),
                    partner = MakeView(10.5, nullptr, 1.0, -1.5), ahead = MakeView(13, nullptr);
  DynamicOptions off;
  off.partners_veto = 0;
  const DynamicEvidence raw = EstimateDynamic(t, {&n}, off, {&partner});
  const DynamicEvidence base = EstimateDynamic(t, {&n}, off, {&partner}, {&ahead});
  int dropped_by_ahead = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      dropped_by_ahead +=
          std::isfinite(raw.across.at<float>(y, x)) && std::isnan(base.across.at<float>(y, x));
  EXPECT_GE(dropped_by_ahead, 3000);  // the order matters on these pixels
  int last = -1;
  for (const double f : {0.5, 1.0, 2.0}) {
    DynamicOptions o;
    o.partners_veto = f;
    const DynamicEvidence e = EstimateDynamic(t, {&n}, o, {&partner}, {&ahead});
    int vetoed = 0, wrong = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const float f0 = base.flow.at<float>(y, x);
        if (!std::isfinite(f0)) continue;
        const bool veto = raw.across.at<float>(y, x) < f * o.threshold;  // NaN: false
        const float f1 = e.flow.at<float>(y, x);
        vetoed += veto;
        wrong += veto ? !std::isnan(f1) : f1 != f0;
      }
    EXPECT_EQ(wrong, 0) << "F = " << f;
    EXPECT_GT(vetoed, last) << "F = " << f;  // a larger F vetoes more
    last = vetoed;
  }
}

TEST(Dynamic, AVehicleOfTheRoadsLumaIsFoundByItsColour) {
  // Boxes of the road's own luma, tinted blue, at other pixels in each neighbour (moving): in
  // the luma the photos are the bare road; in colour, the red channel differs by 0.4 x the luma
  // (about 0.18, 2.8 x --colour-threshold).
  const Box at_t{100, 70, 40, 25};
  const Box a{60, 72, 40, 25}, b{140, 68, 40, 25}, c{20, 75, 40, 25}, d{170, 70, 40, 25};
  const DynamicView t = Tinted(MakeView(10, nullptr), &at_t);
  const DynamicView n1 = Tinted(MakeView(8, nullptr), &a), n2 = Tinted(MakeView(12, nullptr), &b),
                    n3 = Tinted(MakeView(6, nullptr), &c), n4 = Tinted(MakeView(14, nullptr), &d);
  DynamicOptions colour, luma;
  luma.colour = false;
  double recall, fp;
  Score(MaskFromProbability(EstimateDynamic(t, {&n1, &n2, &n3, &n4}, luma).probability,
                            MaskOptions()),
        at_t, recall, fp);
  EXPECT_EQ(recall, 0);
  Score(MaskFromProbability(EstimateDynamic(t, {&n1, &n2, &n3, &n4}, colour).probability,
                            MaskOptions()),
        at_t, recall, fp);
  EXPECT_GE(recall, 0.85);
  EXPECT_LE(fp, 0.01);
  // Another white balance in the neighbours (red +40 %, blue -30 % against the target's): each
  // channel's own gain takes it out; the car is still found and the road is not masked.
  const cv::Vec3d warm{1, 0.95, 0.9}, cold{1.4, 0.95, 0.63};
  const DynamicView tw = Tinted(MakeView(10, nullptr), &at_t, warm);
  const DynamicView w1 = Tinted(MakeView(8, nullptr), &a, cold),
                    w2 = Tinted(MakeView(12, nullptr), &b, cold),
                    w3 = Tinted(MakeView(6, nullptr), &c, cold),
                    w4 = Tinted(MakeView(14, nullptr), &d, cold);
  Score(MaskFromProbability(EstimateDynamic(tw, {&w1, &w2, &w3, &w4}, colour).probability,
                            MaskOptions()),
        at_t, recall, fp);
  EXPECT_GE(recall, 0.85);
  EXPECT_LE(fp, 0.01);
  // A grey neighbour (its three channels equal, as a grey camera's photo is loaded): compared by
  // the luma, where the car is the road.
  const DynamicView g1 = Tinted(MakeView(8, nullptr), &a), g2 = Tinted(MakeView(12, nullptr), &b);
  DynamicView grey1 = g1, grey2 = g2;
  grey1.colour = Tinted(MakeView(8, nullptr), nullptr).colour;
  grey2.colour = Tinted(MakeView(12, nullptr), nullptr).colour;
  Score(
      MaskFromProbability(EstimateDynamic(t, {&grey1, &grey2}, colour).probability, MaskOptions()),
      at_t, recall, fp);
  EXPECT_EQ(recall, 0);
  EXPECT_LE(fp, 0.01);
}

TEST(Dynamic, ExposureChangeIsNotMotion) {
  const DynamicView t = MakeView(10, nullptr);
  const DynamicView n1 = MakeView(9, nullptr, 1.25), n2 = MakeView(11, nullptr, 0.75);
  const DynamicEvidence e = EstimateDynamic(t, {&n1, &n2}, DynamicOptions());
  EXPECT_EQ(cv::countNonZero(e.probability >= 0.5f), 0);
}

TEST(Dynamic, NoNeighbourFlatImageAndSkyGiveNoEvidence) {
  const Box box{100, 70, 40, 25};
  const DynamicView t = MakeView(10, &box);
  const DynamicEvidence none = EstimateDynamic(t, {}, DynamicOptions());
  EXPECT_EQ(none.neighbours, 0);
  EXPECT_EQ(cv::countNonZero(none.probability > 0.f), 0);
  // A textureless road: nothing can be told apart, nothing is masked.
  const DynamicView f = MakeView(10, nullptr, 1, 0, true), g = MakeView(11, nullptr, 1, 0, true);
  EXPECT_EQ(cv::countNonZero(EstimateDynamic(f, {&g}, DynamicOptions()).probability >= 0.5f), 0);
  // Sky (no depth) never has evidence, whatever it shows.
  const DynamicView n = MakeView(11, nullptr);
  const DynamicEvidence e = EstimateDynamic(t, {&n}, DynamicOptions());
  for (int y = 0; y < 50; ++y)
    for (int x = 0; x < kW; ++x) ASSERT_EQ(e.probability.at<float>(y, x), 0.f);
}

TEST(Dynamic, NeighbourThatSeesNothingIsNotCounted) {
  const DynamicView t = MakeView(10, nullptr);
  DynamicView behind = MakeView(10, nullptr);
  behind.world_to_camera =
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY())),
              Eigen::Vector3d(0, 0, 10));  // looks backwards from z = 10
  EXPECT_EQ(EstimateDynamic(t, {&behind}, DynamicOptions()).neighbours, 0);
}

TEST(Dynamic, SimilarWorldsGiveTheSameEvidence) {
  // Scale 0.2 and a UTM-sized offset: the same probabilities.
  // A partner of another drive (with its own depth map) counts too.
  const Box box{100, 70, 40, 25}, a{60, 72, 40, 25}, b{150, 68, 40, 25}, c{30, 66, 40, 25};
  const DynamicView t = MakeView(10, &box), n1 = MakeView(9, &a), n2 = MakeView(11, &b);
  DynamicView p = MakeView(10.5, &c, 1.0, -1.5);
  p.seen = p.depth.clone();
  p.seen(cv::Rect(c.x0, c.y0, c.w, c.h)).setTo(p.depth.at<float>(c.y0 + c.h - 1, c.x0));
  const DynamicEvidence e = EstimateDynamic(t, {&n1, &n2}, DynamicOptions(), {&p});
  EXPECT_EQ(e.partners, 1);
  const Eigen::Vector3d off(451000, 120, 5410000);
  auto moved = [&](DynamicView v) {
    // x_world' = 0.2 x_world + off: t' = 0.2 t - R off, depth 0.2 z.
    v.world_to_camera.t = 0.2 * v.world_to_camera.t - (v.world_to_camera.q * off);
    v.depth *= 0.2;
    if (!v.seen.empty()) v.seen *= 0.2;
    return v;
  };
  const DynamicView t2 = moved(t), m1 = moved(n1), m2 = moved(n2), p2 = moved(p);
  const DynamicEvidence f = EstimateDynamic(t2, {&m1, &m2}, DynamicOptions(), {&p2});
  EXPECT_LE(cv::norm(e.probability, f.probability, cv::NORM_INF), 1e-3);
  cv::Mat ea = e.across.clone(), fa = f.across.clone();  // NaN where no partner saw: -1 in both
  cv::patchNaNs(ea, -1), cv::patchNaNs(fa, -1);
  EXPECT_LE(cv::norm(ea, fa, cv::NORM_INF), 1e-4);
  EXPECT_GT(cv::countNonZero(ea >= 0), 1000);
}

TEST(Dynamic, MaskFromProbabilityFillsAndDropsSpecks) {
  cv::Mat p(100, 200, CV_32F, 0.f);
  cv::rectangle(p, cv::Rect(50, 30, 40, 30), cv::Scalar(0.9),
                3);         // an outline: its inside is a hole
  p.at<float>(5, 5) = 1.f;  // a speck
  const cv::Mat m = MaskFromProbability(p, MaskOptions());
  EXPECT_EQ(m.at<uint8_t>(45, 70), 255);  // the hole is filled
  EXPECT_EQ(m.at<uint8_t>(5, 5), 0);      // the speck is gone
  EXPECT_EQ(m.at<uint8_t>(90, 150), 0);
  EXPECT_EQ(cv::countNonZero(MaskFromProbability(cv::Mat(100, 200, CV_32F, 0.f), MaskOptions())),
            0);
  EXPECT_EQ(cv::countNonZero(MaskFromProbability(cv::Mat(100, 200, CV_32F, 1.f), MaskOptions())),
            200 * 100);  // a full mask stays full
}

// The blob tests' scene: the target of MakeView over a level road (up is -y), a probability map
// holding a patch lying on the road 8 to 14 m ahead (rows 64..74: the rows whose ground is 13.7
// and 8.1 m away) and a vehicle standing 10 m ahead (rows 52..69: its foot row's ground 10.15 m
// away, its top row 1.65 - 2.5 / 120 x 10.15 = 1.44 m above the ground there).
constexpr double kPatchRise = 1 - (198 / 24.5) / (198 / 14.5);  // 0.408 of the camera's height
constexpr double kVehicleRise = (1.65 - 2.5 / 120 * (198 / 19.5)) / 1.65;  // 0.872
const cv::Rect kPatch(20, 64, 41, 11), kVehicle(150, 52, 51, 18);

cv::Mat BlobTestProbability() {
  cv::Mat p(kH, kW, CV_32F, 0.f);
  p(kPatch).setTo(0.9f);
  p(kVehicle).setTo(0.9f);
  return p;
}

// The rotation of the blob tests' similar world, and a view moved into that world: turned by q,
// scaled by 0.2 and moved to UTM-sized coordinates (its depth scaled alike).
Eigen::Quaterniond SimilarWorldRotation() {
  return Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 1, 0.1).normalized()));
}
DynamicView InSimilarWorld(const DynamicView& t, const Eigen::Quaterniond& q) {
  DynamicView m = t;
  m.world_to_camera.q = t.world_to_camera.q * q.inverse();
  m.world_to_camera.t =
      0.2 * t.world_to_camera.t - m.world_to_camera.q * Eigen::Vector3d(451000, 120, 5410000);
  m.depth = t.depth * 0.2;
  return m;
}

MaskOptions ExactBlobs() {  // no opening, closing or size limit: the rectangles as they are
  MaskOptions m;
  m.open = 0, m.close = 0, m.min_area = 0;
  return m;
}

TEST(Dynamic, BlobsLyingInTheRoadGoThoseStandingStay) {
  const DynamicView t = MakeView(10, nullptr);
  const Eigen::Vector3d up(0, -1, 0);
  const auto run = [&](const DynamicView& v, const Eigen::Vector3d& u, double min_height,
                       int& lying) {
    cv::Mat p = BlobTestProbability();
    lying = KeepStandingUnexplained(v, u, ExactBlobs(), {min_height, 0, 0}, p).lying;
    return std::pair<bool, bool>{p.at<float>(70, 40) > 0, p.at<float>(60, 170) > 0};
  };
  int lying = 0;
  // Thresholds just either side of each blob's hand-derived rise.
  EXPECT_EQ(run(t, up, kPatchRise - 0.01, lying), std::make_pair(true, true));
  EXPECT_EQ(lying, 0);
  EXPECT_EQ(run(t, up, kPatchRise + 0.01, lying), std::make_pair(false, true));
  EXPECT_EQ(lying, 1);
  EXPECT_EQ(run(t, up, kVehicleRise - 0.01, lying), std::make_pair(false, true));
  EXPECT_EQ(run(t, up, kVehicleRise + 0.01, lying), std::make_pair(false, false));
  EXPECT_EQ(lying, 2);
  EXPECT_EQ(run(t, up, 0, lying), std::make_pair(true, true));  // off
  // A similar world (rotated, scale 0.2, UTM-sized offset): the same decisions.
  const Eigen::Quaterniond q = SimilarWorldRotation();
  const DynamicView m = InSimilarWorld(t, q);
  EXPECT_EQ(run(m, q * up, kPatchRise + 0.01, lying), std::make_pair(false, true));
  EXPECT_EQ(run(m, q * up, kVehicleRise - 0.01, lying), std::make_pair(false, true));
  EXPECT_EQ(run(m, q * up, kVehicleRise + 0.01, lying), std::make_pair(false, false));
  // Without the road's points in the image's lower middle, no camera height: nothing judged.
  DynamicView sky = t;
  sky.depth = cv::Mat(kH, kW, CV_32F, std::numeric_limits<float>::infinity());
  EXPECT_EQ(run(sky, up, 0.9, lying), std::make_pair(true, true));
  EXPECT_EQ(lying, 0);
}

// A facade across the road 9.9 m ahead in columns 20..99 (its foot on the road at row 69: the
// ground 198 / (y - 49.5) m away), a door on it (rows 40..69, columns 40..60), a vehicle in front
// of it (rows 50..79, columns 70..95: its foot row's ground 198 / 29.5 = 6.71 m away, its upper
// half seeing the facade: 9.9 / 6.71 = 1.475 times as deep) and a blob in the sky (no foot).
constexpr double kWallDepth = 9.9, kVehicleBehind = kWallDepth / (198 / 29.5);
const cv::Rect kDoor(40, 40, 21, 30), kFront(70, 50, 26, 30), kCloud(150, 5, 30, 10);

TEST(Dynamic, BlobsOnTheStaticSurfaceGoThoseHidingItStay) {
  DynamicView t = MakeView(10, nullptr);
  t.depth(cv::Rect(20, 0, 80, 70)).setTo(float(kWallDepth));
  const Eigen::Vector3d up(0, -1, 0);
  const auto run = [&](const DynamicView& v, double occludes, double gap, int& surface) {
    cv::Mat p(kH, kW, CV_32F, 0.f);
    for (const cv::Rect& r : {kDoor, kFront, kCloud}) p(r).setTo(0.9f);
    surface = KeepStandingUnexplained(v, up, ExactBlobs(), {0, 0, occludes, gap}, p).surface;
    return std::array<bool, 3>{p.at<float>(55, 50) > 0, p.at<float>(60, 80) > 0,
                               p.at<float>(10, 160) > 0};
  };
  int surface = 0;
  using B = std::array<bool, 3>;
  // The door hides nothing: every upper pixel is as deep as its foot.
  EXPECT_EQ(run(t, 0.2, 0.25, surface), (B{false, true, true}));
  EXPECT_EQ(surface, 1);
  // The vehicle's gap, either side of the hand-derived 1.475.
  EXPECT_EQ(run(t, 0.2, kVehicleBehind - 1 - 0.01, surface), (B{false, true, true}));
  EXPECT_EQ(run(t, 0.2, kVehicleBehind - 1 + 0.01, surface), (B{false, false, true}));
  EXPECT_EQ(surface, 2);                                          // the sky blob has no foot: kept
  EXPECT_EQ(run(t, 1.0, 0.25, surface), (B{false, true, true}));  // all its upper pixels
  EXPECT_EQ(run(t, 0, 0.25, surface), (B{true, true, true}));     // off
  EXPECT_EQ(surface, 0);
  // A similar world (scale 0.2, UTM-sized offset, rotated): the same decisions.
  const DynamicView m = InSimilarWorld(t, SimilarWorldRotation());
  EXPECT_EQ(run(m, 0.2, kVehicleBehind - 1 - 0.01, surface), (B{false, true, true}));
  EXPECT_EQ(run(m, 0.2, kVehicleBehind - 1 + 0.01, surface), (B{false, false, true}));
  // The depth behind is part of the evidence: with the road everywhere (no facade), the door's
  // upper pixels see the road far behind its foot and it stays.
  EXPECT_EQ(run(MakeView(10, nullptr), 0.2, 0.25, surface), (B{true, true, true}));
  cv::Mat p(kH, kW, CV_32F, 0.f);
  EXPECT_THROW(KeepStandingUnexplained(t, up, ExactBlobs(), {0, 0, 1.5, 0.25}, p), Error);
  EXPECT_THROW(KeepStandingUnexplained(t, up, ExactBlobs(), {0, 0, 0.2, 0}, p), Error);
}

TEST(Dynamic, PixelsThePhotosOwnDepthExplainsAreCleared) {
  DynamicView t = MakeView(10, nullptr);
  const Eigen::Vector3d up(0, -1, 0);
  cv::Mat p = BlobTestProbability();
  // No depth of its own: nothing cleared.
  EXPECT_EQ(KeepStandingUnexplained(t, up, ExactBlobs(), {0, 0.05, 0}, p).explained, 0u);
  EXPECT_EQ(cv::countNonZero(p > 0), kPatch.area() + kVehicle.area());
  // Densify found the road under the patch (within 4 %) and the vehicle nearer than the road.
  t.seen = t.depth * 1.04f;
  t.seen(kVehicle) = t.depth(kVehicle) * 0.6f;
  EXPECT_EQ(KeepStandingUnexplained(t, up, ExactBlobs(), {0, 0.05, 0}, p).explained,
            size_t(kPatch.area()));
  EXPECT_EQ(cv::countNonZero(p(kPatch) > 0), 0);
  EXPECT_EQ(cv::countNonZero(p(kVehicle) > 0), kVehicle.area());
  // A tighter tolerance than the 4 % leaves the patch; 0 turns the test off.
  for (double tol : {0.03, 0.0}) {
    cv::Mat q = BlobTestProbability();
    EXPECT_EQ(KeepStandingUnexplained(t, up, ExactBlobs(), {0, tol, 0}, q).explained, 0u);
    EXPECT_EQ(cv::countNonZero(q > 0), kPatch.area() + kVehicle.area());
  }
  cv::Mat small(10, 10, CV_32F, 0.f);
  EXPECT_THROW(KeepStandingUnexplained(t, up, ExactBlobs(), {0.5, 0.05}, small), Error);
  EXPECT_THROW(KeepStandingUnexplained(t, up, ExactBlobs(), {-1, 0.05}, p), Error);
  EXPECT_THROW(KeepStandingUnexplained(t, up, ExactBlobs(), {0.5, 1}, p), Error);
}

// Where the static depth is a guess (a corridor wall roadmesh --dense puts behind a hole of the
// fused facades), a blob mostly there is cleared there: the patch wholly on a guess goes, the
// vehicle whose top third hides a guessed wall keeps its body; shares from the rectangles' sizes.
TEST(Dynamic, BlobsMostlyOnAGuessedDepthAreClearedThere) {
  DynamicView t = MakeView(10, nullptr);
  const Eigen::Vector3d up(0, -1, 0);
  t.guessed = cv::Mat::zeros(kH, kW, CV_8U);
  t.guessed(kPatch).setTo(255);
  t.guessed(cv::Rect(kVehicle.x, kVehicle.y, kVehicle.width, kVehicle.height / 3)).setTo(255);
  cv::Mat p = BlobTestProbability();
  EXPECT_EQ(KeepStandingUnexplained(t, up, ExactBlobs(), {0, 0, 0, 0.25, 0.5}, p).guessed, 1);
  EXPECT_EQ(cv::countNonZero(p(kPatch) > 0), 0);
  EXPECT_EQ(cv::countNonZero(p(kVehicle) > 0), kVehicle.area());
  // The patch's left 20 of 41 columns on a guess (0.488): kept at 0.5; at 0.4 cleared there
  // only, its other columns kept. 1 turns the test off; without the mask nothing is judged.
  t.guessed.setTo(0);
  t.guessed(cv::Rect(kPatch.x, kPatch.y, 20, kPatch.height)).setTo(255);
  for (double s : {0.5, 0.4, 1.0}) {
    cv::Mat q = BlobTestProbability();
    const int n = KeepStandingUnexplained(t, up, ExactBlobs(), {0, 0, 0, 0.25, s}, q).guessed;
    const bool cleared = s == 0.4;
    EXPECT_EQ(n, cleared ? 1 : 0) << s;
    EXPECT_EQ(cv::countNonZero(q(kPatch) > 0), cleared ? 21 * kPatch.height : kPatch.area()) << s;
  }
  DynamicView none = MakeView(10, nullptr);
  cv::Mat q = BlobTestProbability();
  EXPECT_EQ(KeepStandingUnexplained(none, up, ExactBlobs(), {0, 0, 0, 0.25, 0}, q).guessed, 0);
  EXPECT_EQ(cv::countNonZero(q > 0), kPatch.area() + kVehicle.area());
  EXPECT_THROW(KeepStandingUnexplained(t, up, ExactBlobs(), {0, 0, 0, 0.25, 1.5}, q), Error);
  t.guessed = cv::Mat::zeros(kH, kW, CV_32F);  // not 8-bit
  EXPECT_THROW(KeepStandingUnexplained(t, up, ExactBlobs(), {0, 0, 0, 0.25, 0.5}, q), Error);
}

// A red object on a textured green ground: the evidence found its lower part (rows 75-99); its
// upper part (rows 40-74) shows none. GrabCut seeded with the blob grows it within the box
// widened by half its width each side and by its height upwards (x 80-159, rows 50-99, its border
// sure background): O's rows 51-99 exactly (40 x 49 pixels). A red patch touching O (x 140-154,
// rows 70-94) that the photo's own depth explains stays out; unexplained, it is taken too (15 x
// 25 more). Masked: at or above the mask's probability (0.4), to which grown pixels are raised.
TEST(Dynamic, BlobsAreCompletedFromTheirColoursNeverIntoExplainedPixels) {
  DynamicView t = MakeView(10, nullptr);
  const cv::Rect object(100, 40, 40, 60), found(100, 75, 40, 25), patch(140, 70, 15, 25);
  t.colour.create(kH, kW, CV_8UC3);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      t.colour.at<cv::Vec3b>(y, x) =
          cv::Vec3b(uchar(40 + (x * 7 + y * 13) % 40), uchar(120 + (x * 3 + y) % 30), 60);
  for (const cv::Rect& r : {object, patch})
    for (int y = r.y; y < r.y + r.height; ++y)
      for (int x = r.x; x < r.x + r.width; ++x)
        t.colour.at<cv::Vec3b>(y, x) = cv::Vec3b(uchar(195 + (x + 2 * y) % 10), 30, 30);
  t.seen = t.depth.clone();
  t.seen(object).setTo(std::numeric_limits<float>::infinity());  // moving: no consistent depth
  const auto run = [&](const BlobCompletion& o, int& completed) {
    cv::Mat p = cv::Mat::zeros(kH, kW, CV_32F);
    p(found).setTo(1);
    completed = CompleteBlobs(t, ExactBlobs(), o, p);
    return cv::Mat(p >= ExactBlobs().probability);
  };
  int n = 0;
  cv::Mat m = run({}, n);
  EXPECT_EQ(n, 1);
  const cv::Rect reach(100, 51, 40, 49);
  EXPECT_EQ(cv::countNonZero(m(reach)), reach.area());
  EXPECT_EQ(cv::countNonZero(m), reach.area());
  // Nothing explained: the patch of the object's colour joins it.
  const cv::Mat explained = t.seen.clone();
  t.seen.setTo(std::numeric_limits<float>::infinity());
  m = run({}, n);
  EXPECT_EQ(n, 1);
  EXPECT_EQ(cv::countNonZero(m(reach)), reach.area());
  EXPECT_EQ(cv::countNonZero(m(patch)), patch.area());
  EXPECT_EQ(cv::countNonZero(m), reach.area() + patch.area());
  t.seen = explained;
  // Growth capped (960 more pixels than the blob's 1000: not at 0.9), off, or without the
  // photo's depth: the blob as found.
  BlobCompletion capped;
  capped.max_grow = 0.9;
  for (const BlobCompletion& o : {capped, BlobCompletion{0, 0.05, 3}}) {
    m = run(o, n);
    EXPECT_EQ(n, 0);
    EXPECT_EQ(cv::countNonZero(m), found.area());
  }
  t.seen = cv::Mat();
  m = run({}, n);
  EXPECT_EQ(n, 0);
  EXPECT_EQ(cv::countNonZero(m), found.area());
  cv::Mat p = cv::Mat::zeros(kH, kW, CV_32F);
  EXPECT_THROW(CompleteBlobs(t, ExactBlobs(), {3, 1.5, 3}, p), Error);
  p = cv::Mat::zeros(kH / 2, kW, CV_32F);
  EXPECT_THROW(CompleteBlobs(t, ExactBlobs(), {}, p), Error);
}

// A vehicle's rear standing 10 m ahead, 1 m either side of the camera's line and 1.4 m high
// (world x -1..1, y 0.25..1.65 under the camera's y-down axes, z 10): the static depth and the
// photo's own depth both see it. Hand-derived: its pixels are columns 108..131 (x = (col + 0.5 -
// 120) / 120 × 10 within +-1) and rows 53..69; the rows whose point rises more than 0.15 × 1.65
// = 0.2475 m above the road are 53..66 (row 66: 1.65 - 16.5 / 12 = 0.275 m; row 67: 0.192 m),
// all below 1.2 × 1.65: 14 × 24 = 336 pixels.
DynamicView StandingFaceView(double x0, double x1) {
  DynamicView v = MakeView(0, nullptr);
  const Camera& c = v.camera;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const double X = (x + 0.5 - c.cx()) / c.fx() * 10, Y = (y + 0.5 - c.cy()) / c.fy() * 10;
      if (X >= x0 && X <= x1 && Y >= 0.25 && Y <= kHeight) v.depth.at<float>(y, x) = 10;
    }
  v.seen = v.depth.clone();
  return v;
}

// Camera centres along the camera's line (world x 0, y `y`) from z0 to z1, every 2 m, 1.65 m
// above their road.
DrivenPath StraightPath(double z0, double z1, double y = 0) {
  DrivenPath p;
  for (double z = z0; z <= z1 + 1e-9; z += 2) p.centres.emplace_back(0, y, z);
  p.height = kHeight;
  return p;
}

TEST(Dynamic, SurfacesStandingWhereACarDroveAreMarked) {
  const Eigen::Vector3d up(0, -1, 0);
  DrivenSpace exact;  // no opening, no size limit: the pixels as they are
  exact.open = 0, exact.min_area = 0;
  const auto run = [&](const DynamicView& v, const std::vector<DrivenPath>& paths,
                       const DrivenSpace& o, const Eigen::Vector3d& u) {
    cv::Mat p(kH, kW, CV_32F, 0.f);
    const size_t n = MarkDriven(v, paths, u, o, p);
    EXPECT_EQ(size_t(cv::countNonZero(p == 1.f)), n);
    return p;
  };
  const auto count = [&](const DynamicView& v, const std::vector<DrivenPath>& paths,
                         const DrivenSpace& o) { return cv::countNonZero(run(v, paths, o, up)); };
  const DynamicView face = StandingFaceView(-1, 1);
  cv::Mat p = run(face, {StraightPath(-10, 30)}, exact, up);
  const cv::Rect truth(108, 53, 24, 14);
  EXPECT_EQ(cv::countNonZero(p(truth) == 1.f), 336);
  EXPECT_EQ(cv::countNonZero(p == 1.f), 336);
  // Where no car drove: the path ends 1 m before it, or begins 1 m after it (within 1.65 m of
  // the path's end, but beyond it), also where the car stood still at its end; it begins 5 m
  // before it (the camera itself off the path: the face still beside it); a second path that
  // passes it marks it whatever the first does.
  EXPECT_EQ(count(face, {StraightPath(-21, 9)}, exact), 0);
  EXPECT_EQ(count(face, {StraightPath(11, 31)}, exact), 0);
  DrivenPath stood = StraightPath(-21, 9);
  stood.centres.push_back(stood.centres.back());
  EXPECT_EQ(count(face, {stood}, exact), 0);
  EXPECT_EQ(count(face, {StraightPath(5, 30)}, exact), 336);
  EXPECT_EQ(count(face, {StraightPath(-21, 9), StraightPath(5, 30)}, exact), 336);
  // The road under a path is its camera's height below it: a drive 1 m higher (its road 1 m
  // above this one) takes rises 1 m lower: only rows 53..54 rise more than 0.2475 m above its
  // road (row 54: Y = 4.5 / 12 = 0.375, 1.275 - 1 m; row 55: 1.192 - 1 m), 2 × 24 = 48; the
  // ground under it is not in its space.
  EXPECT_EQ(count(face, {StraightPath(-10, 30, -1)}, exact), 48);
  // --driven-below 0.5 (0.825 m): rows 60..66 (row 60: rise 1.65 - 10.5 / 12 = 0.775 m; row
  // 59: 0.858 m), 7 × 24 = 168. A path without a camera height: nothing.
  DrivenSpace low = exact;
  low.below = 0.5;
  EXPECT_EQ(count(face, {StraightPath(-10, 30)}, low), 168);
  DrivenPath no_height = StraightPath(-10, 30);
  no_height.height = 0;
  EXPECT_EQ(count(face, {no_height}, exact), 0);
  // A face 2 to 4 m to the side: beyond 1 × 1.65 m of the path, within 2.5 × 1.65 m (columns
  // 144..167).
  const DynamicView side = StandingFaceView(2, 4);
  EXPECT_EQ(count(side, {StraightPath(-10, 30)}, exact), 0);
  DrivenSpace wide = exact;
  wide.half_width = 2.5;
  p = run(side, {StraightPath(-10, 30)}, wide, up);
  EXPECT_EQ(cv::countNonZero(p(cv::Rect(144, 53, 24, 14)) == 1.f), 336);
  EXPECT_EQ(cv::countNonZero(p), 336);
  // The photo saw it but the mesh has the road there (a lone photo's stereo mistake), or the
  // photo saw nothing: nothing marked. The road alone: nothing.
  DynamicView lone = face;
  lone.depth = MakeView(0, nullptr).depth;
  EXPECT_EQ(count(lone, {StraightPath(-10, 30)}, exact), 0);
  lone = face;
  lone.seen = cv::Mat();
  EXPECT_EQ(count(lone, {StraightPath(-10, 30)}, exact), 0);
  DynamicView road = MakeView(0, nullptr);
  road.seen = road.depth.clone();
  EXPECT_EQ(count(road, {StraightPath(-10, 30)}, exact), 0);
  // Specks go with the masks' opening and size limit: a face one column wide goes with the
  // opening; the face stays but for the corners the opening's cross takes (grown back from the
  // mesh's surface), and goes under a size limit of 2 % of the image (576 pixels).
  DrivenSpace masks;
  EXPECT_EQ(count(StandingFaceView(-0.1, 0.0), {StraightPath(-10, 30)}, masks), 0);
  masks.grow = false;
  EXPECT_EQ(count(face, {StraightPath(-10, 30)}, masks), 336 - 4);
  masks.grow = true;
  EXPECT_EQ(count(face, {StraightPath(-10, 30)}, masks), 336);
  DrivenSpace large = exact;
  large.min_area = 0.02;
  EXPECT_EQ(count(face, {StraightPath(-10, 30)}, large), 0);
  // The same in a similar world (turned, scaled by 0.2, at UTM-sized coordinates).
  const Eigen::Quaterniond q = SimilarWorldRotation();
  DynamicView moved = InSimilarWorld(face, q);
  moved.seen = face.seen * 0.2;
  DrivenPath path = StraightPath(-10, 30);
  for (Eigen::Vector3d& c : path.centres) c = q * (0.2 * c) + Eigen::Vector3d(451000, 120, 5410000);
  path.height *= 0.2;
  p = run(moved, {path}, exact, q * up);
  EXPECT_EQ(cv::countNonZero(p(truth) == 1.f), 336);
  EXPECT_EQ(cv::countNonZero(p), 336);
  DrivenSpace bad = exact;
  bad.agree = 0;
  EXPECT_THROW(run(face, {path}, bad, up), Error);
}

TEST(Dynamic, TheRestOfASurfaceWhereACarDroveIsMarked) {
  const Eigen::Vector3d up(0, -1, 0);
  DrivenSpace exact;
  exact.open = 0, exact.min_area = 0;
  const auto count = [&](const DynamicView& v, const DrivenSpace& o, double z0 = -10) {
    cv::Mat p(kH, kW, CV_32F, 0.f);
    const size_t n = MarkDriven(v, {StraightPath(z0, 30)}, up, o, p);
    EXPECT_EQ(size_t(cv::countNonZero(p == 1.f)), n);
    return cv::countNonZero(p == 1.f);
  };
  // The face of SurfacesStandingWhereACarDroveAreMarked (rows 53..66 of columns 108..131 in the
  // space), the photo's depth on its top three rows only: no depth below (a dark body), or
  // another surface 5 m behind it (a window). Grown: the whole face, 336 pixels; not: 3 × 24.
  DynamicView face = StandingFaceView(-1, 1);
  face.seen(cv::Rect(0, 56, kW, kH - 56)).setTo(std::numeric_limits<float>::infinity());
  EXPECT_EQ(count(face, exact), 336);
  DrivenSpace seeds = exact;
  seeds.grow = false;
  EXPECT_EQ(count(face, seeds), 72);
  face.seen(cv::Rect(0, 56, kW, kH - 56)).setTo(15.f);
  EXPECT_EQ(count(face, exact), 336);
  // Not beyond the space: the ground under the face and the road are the mesh's too, and it
  // does not grow over them. Nothing to grow from: the photo's depth nowhere on the face, or
  // the path beginning 1 m beyond it. A corridor wall (a guessed depth) is not grown over.
  face.seen.setTo(std::numeric_limits<float>::infinity());
  EXPECT_EQ(count(face, exact), 0);
  face = StandingFaceView(-1, 1);
  face.seen(cv::Rect(0, 56, kW, kH - 56)).setTo(std::numeric_limits<float>::infinity());
  EXPECT_EQ(count(face, exact, 11), 0);
  face.guessed = cv::Mat(kH, kW, CV_8U, cv::Scalar(0));
  face.guessed(cv::Rect(0, 56, kW, kH - 56)).setTo(1);
  EXPECT_EQ(count(face, exact), 72);
  face.guessed = cv::Mat();
  // A second face (columns 160..167, 3.3..4 m right of the path: within 2.5 × 1.65 m of it)
  // with no depth of its own, 28 columns of far ground from the first: not grown into.
  DrivenSpace wide = exact;
  wide.half_width = 2.5;
  const DynamicView right = StandingFaceView(3.3, 4);
  right.depth.copyTo(face.depth, right.depth == 10.f);
  EXPECT_EQ(count(face, wide), 336);
  face.seen(cv::Rect(160, 53, 8, 3)).setTo(10.f);
  EXPECT_EQ(count(face, wide), 336 + 8 * 14);
}

TEST(Dynamic, AWholeImageBlobIsNotCompleted) {
  // Nothing outside it to model the background from (a full mask): left as it is.
  DynamicView t = MakeView(10, nullptr);
  t.colour = cv::Mat(kH, kW, CV_8UC3, cv::Scalar(90, 120, 60));
  t.seen = t.depth.clone();
  t.seen.setTo(std::numeric_limits<float>::infinity());
  cv::Mat p(kH, kW, CV_32F, 1.f);
  EXPECT_EQ(CompleteBlobs(t, ExactBlobs(), {}, p), 0);
  EXPECT_EQ(cv::countNonZero(p == 1.f), kW * kH);
}

TEST(Dynamic, BadInputs) {
  DynamicView t = MakeView(10, nullptr);
  t.depth = cv::Mat(10, 10, CV_32F, 1.f);
  EXPECT_THROW(EstimateDynamic(t, {}, DynamicOptions()), Error);
  DynamicOptions o;
  o.window = 4;
  EXPECT_THROW(o.Check(), UsageError);
  for (double veto : {-0.1, 10.5, std::numeric_limits<double>::quiet_NaN()}) {
    DynamicOptions p;
    p.partners_veto = veto;
    EXPECT_THROW(p.Check(), UsageError) << veto;
  }
  MaskOptions m;
  m.probability = 1;
  EXPECT_THROW(m.Check(), UsageError);
}

}  // namespace
}  // namespace mvtm
