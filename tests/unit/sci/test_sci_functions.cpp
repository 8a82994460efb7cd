// The SCI's functions: the image box (eq. 4.33, 4.34), its face picking and placing
// on the target; the suture thread's explicit Euler mass-spring model.
#include <gtest/gtest.h>

#include <cmath>

#include "endotower/sci/sci_functions.hpp"
#include "endotower/sci/sci_machine.hpp"

namespace endotower::sci {
namespace {

TEST(OrientationAngles, Eq434) {
    const Vec3d a = orientation_angles_deg({0, 0, 1});
    EXPECT_DOUBLE_EQ(a.x, 0);
    EXPECT_DOUBLE_EQ(a.y, 0);
    EXPECT_DOUBLE_EQ(a.z, 90);
    const double s = std::sqrt(0.5);
    const Vec3d b = orientation_angles_deg({s, 0, s});
    EXPECT_NEAR(b.x, 45, 1e-12);
    EXPECT_NEAR(b.y, 0, 1e-12);
    EXPECT_NEAR(b.z, 45, 1e-12);
}

TEST(ImageBox, StartsAt80mmAndFollowsThePoseDeltas) {
    ImageBox box;
    box.reset();
    EXPECT_DOUBLE_EQ(box.position_mm().z, 80);
    const std::array<float, 16> m0 = box.camera_from_model();
    EXPECT_FLOAT_EQ(m0[0], 1);
    EXPECT_FLOAT_EQ(m0[5], 1);
    EXPECT_FLOAT_EQ(m0[10], 1);
    EXPECT_FLOAT_EQ(m0[14], 80);
    box.follow({1, 2, 3}, {0, 0, 1});  // not grabbed: stays
    EXPECT_DOUBLE_EQ(box.position_mm().x, 0);
    box.grab({10, 5, 70}, {0, 0, 1});
    const double s = std::sqrt(0.5);
    box.follow({15, 2, 80}, {s, 0, s});
    // Eq. 4.33: T_n - T_o = (5, -3, 10); R_n - R_o = (45, 0, -45).
    EXPECT_DOUBLE_EQ(box.position_mm().x, 5);
    EXPECT_DOUBLE_EQ(box.position_mm().y, -3);
    EXPECT_DOUBLE_EQ(box.position_mm().z, 90);
    EXPECT_NEAR(box.angles_deg().x, 45, 1e-12);
    EXPECT_NEAR(box.angles_deg().y, 0, 1e-12);
    EXPECT_NEAR(box.angles_deg().z, -45, 1e-12);
    // Rz(-45) Rx(45) applied to +x: (cos -45, sin -45, 0).
    const std::array<float, 16> m = box.camera_from_model();
    EXPECT_NEAR(m[0], s, 1e-6);
    EXPECT_NEAR(m[1], -s, 1e-6);
    EXPECT_NEAR(m[2], 0, 1e-6);
    EXPECT_FLOAT_EQ(m[12], 5);
    EXPECT_FLOAT_EQ(m[14], 90);
}

TEST(ImageBox, PlacesOnTheTargetOnlyWithinTolerance) {
    ImageBox box;
    box.grab({0, 0, 60}, {0, 0, 1});
    box.follow({15, 10, 68}, {0, 0, 1});  // centre (15, 10, 88): 5.39 mm from the target
    EXPECT_TRUE(box.place({20, 10, 90}, 10));
    EXPECT_FALSE(box.grabbed());
    EXPECT_DOUBLE_EQ(box.position_mm().x, 20);
    EXPECT_DOUBLE_EQ(box.position_mm().z, 90);
    ImageBox far;
    far.grab({0, 0, 60}, {0, 0, 1});
    far.follow({-20, 0, 60}, {0, 0, 1});
    EXPECT_FALSE(far.place({20, 10, 90}, 10));
    EXPECT_DOUBLE_EQ(far.position_mm().x, -20);
}

// Issue 8 with a tracked region: the target marker rides on the tissue, and a box placed
// on it stays on it as the tissue moves, until it is grabbed again; a box released off
// the target does not follow.
TEST(ImageBox, PlacedBoxStaysOnAMovingTarget) {
    SciMachine m;
    m.set_box_target({-10, 5, 85});  // the region's centre on the tissue
    EXPECT_DOUBLE_EQ(m.box_target_mm().x, -10);
    EXPECT_DOUBLE_EQ(m.box().position_mm().z, ImageBox::kDepthMm);  // not placed: stays put
    ImageBox box;
    box.grab({0, 0, 60}, {0, 0, 1});
    box.follow({-8, 3, 64}, {0, 0, 1});  // centre (-8, 3, 84): 3 mm from the target
    ASSERT_TRUE(box.place({-10, 5, 85}, 10));
    EXPECT_TRUE(box.placed());
    box.stay_on({-4, 7, 95});  // the endoscope moved: the tissue is elsewhere now
    EXPECT_DOUBLE_EQ(box.position_mm().x, -4);
    EXPECT_DOUBLE_EQ(box.position_mm().y, 7);
    EXPECT_DOUBLE_EQ(box.position_mm().z, 95);
    box.grab({0, 0, 60}, {0, 0, 1});  // picked up again: no longer on the tissue
    EXPECT_FALSE(box.placed());
    box.stay_on({30, 30, 120});
    EXPECT_DOUBLE_EQ(box.position_mm().x, -4);
    ImageBox off;
    off.grab({0, 0, 60}, {0, 0, 1});
    off.follow({40, 0, 60}, {0, 0, 1});
    EXPECT_FALSE(off.place({-10, 5, 85}, 10));
    off.stay_on({-4, 7, 95});
    EXPECT_DOUBLE_EQ(off.position_mm().x, 40);
}

TEST(ImageBox, FaceUnderAPixel) {
    hal::SceneCamera cam{500, 500, 320, 240};
    ImageBox box;
    box.reset();
    // The front face (-z, index 5) is at 60 mm: +-20 mm = +-166.7 px about the centre.
    EXPECT_EQ(box.face_under(320, 240, cam), 5);
    EXPECT_EQ(box.face_under(320 + 160, 240 + 160, cam), 5);
    // Right of it: the +x side face faces away from a camera on the cube's axis.
    EXPECT_EQ(box.face_under(320 + 170, 240, cam), -1);
    EXPECT_EQ(box.face_under(100, 240, cam), -1);
    box.grab({0, 0, 0}, {0, 0, 1});
    box.follow({-60, 0, 0}, {0, 0, 1});  // centre (-60, 0, 80): the +x face turns to the camera
    // +x face: x = -40, z from 60 to 100: px from 320 - 333.3 to 320 - 200; the front
    // face ends at 320 - 333.3.
    EXPECT_EQ(box.face_under(320 - 250, 240, cam), 0);
    EXPECT_EQ(box.face_under(320 - 150, 240, cam), -1);
    EXPECT_EQ(box.face_under(320, 240, hal::SceneCamera{}), -1);
}

TEST(SutureThread, StraightAtRestLengthStaysStraightWithoutGravity) {
    SutureParams p;
    p.gravity_mm_s2 = 0;
    SutureThread t(p);
    const Vec3d a{0, 0, 80}, b{60, 0, 80};  // exactly the rest length
    t.reset(a, b);
    t.step(a, b, 1.0);
    for (int i = 0; i < SutureThread::kNodes; ++i) {
        EXPECT_NEAR(t.nodes()[i].x, 4.0 * i, 1e-9);
        EXPECT_NEAR(t.nodes()[i].y, 0, 1e-12);
    }
}

TEST(SutureThread, ExplicitEulerFirstSteps) {
    SutureThread t;  // gravity 2000 mm/s^2
    const Vec3d a{0, 0, 80}, b{60, 0, 80};
    t.reset(a, b);
    // Sub-step 1: x += v dt (v = 0), v += g dt. Sub-step 2: x += g dt^2 (no spring force yet).
    t.step(a, b, 2 * SutureThread::kStepS);
    const double dt = SutureThread::kStepS;
    for (int i = 1; i + 1 < SutureThread::kNodes; ++i)
        EXPECT_NEAR(t.nodes()[i].y, 2000 * dt * dt, 1e-12);
    EXPECT_DOUBLE_EQ(t.nodes()[0].y, 0);
    EXPECT_DOUBLE_EQ(t.nodes()[SutureThread::kNodes - 1].y, 0);
}

TEST(SutureThread, SettlesIntoASymmetricSagAndFollowsTheTips) {
    SutureThread t;
    Vec3d a{0, 0, 80}, b{50, 0, 80};  // slack: 10 mm shorter than the thread
    t.reset(a, b);
    t.step(a, b, 5.0 / 5);
    for (int k = 0; k < 4; ++k) t.step(a, b, 1.0);
    const auto& n = t.nodes();
    const int last = SutureThread::kNodes - 1;
    for (int i = 0; i <= last; ++i) EXPECT_NEAR(n[i].y, n[last - i].y, 1e-6);
    // Hangs down: an inextensible 60 mm catenary between ends 50 mm apart sags 14.6 mm
    // (a = 23.6 mm); the springs only lengthen it under its weight (about 1 mm per end
    // segment). Explicit Euler stays bounded (no blow-up).
    EXPECT_GT(n[last / 2].y, 14.6);
    EXPECT_LT(n[last / 2].y, 25);
    // The ends are pinned to the tips as they move.
    b = {40, 5, 70};
    t.step(a, b, 0.04);
    EXPECT_DOUBLE_EQ(t.nodes()[last].x, 40);
    EXPECT_DOUBLE_EQ(t.nodes()[last].z, 70);
}

}  // namespace
}  // namespace endotower::sci
