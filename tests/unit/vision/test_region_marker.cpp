// RegionMarker: outlining a region with the tool tip, on exact virtual times.
#include <gtest/gtest.h>

#include <vector>

#include "endotower/vision/region_marker.hpp"

using endotower::hal::ControlEvent;
using endotower::hal::Nanos;
using endotower::vision::Point2;
using endotower::vision::RegionMarker;
using Event = RegionMarker::Event;

namespace {

constexpr Nanos kMs = 1'000'000;
const std::vector<ControlEvent> kNone;

ControlEvent press(Nanos t, ControlEvent::Kind k = ControlEvent::Kind::kButtonPress) {
    ControlEvent e;
    e.kind = k;
    e.time_ns = t;
    return e;
}

// Feeds the tip at `p` every 20 ms from `t0` up to and including `t1`; returns the
// time of the first vertex event, or -1.
Nanos hold(RegionMarker& m, Point2 p, Nanos t0, Nanos t1, Event want = Event::kVertex) {
    for (Nanos t = t0; t <= t1; t += 20 * kMs)
        if (m.update(&p, kNone, t) == want) return t;
    return -1;
}

}  // namespace

TEST(RegionMarker, ButtonPressesPlaceVerticesAndALongPressCloses) {
    RegionMarker m;
    m.begin();
    const std::vector<Point2> corners{{100, 100}, {300, 110}, {280, 260}, {90, 240}};
    Nanos t = 0;
    for (const Point2& c : corners) {
        std::vector<ControlEvent> ev{press(t)};
        EXPECT_EQ(m.update(&c, ev, t), Event::kVertex);
        t += 500 * kMs;
    }
    ASSERT_EQ(m.vertices().size(), 4u);
    std::vector<ControlEvent> lp{press(t, ControlEvent::Kind::kLongPress)};
    const Point2 anywhere{500, 500};
    EXPECT_EQ(m.update(&anywhere, lp, t), Event::kClosed);
    EXPECT_FALSE(m.marking());
    std::array<Point2, RegionMarker::kMaxVertices> poly{};
    std::size_t n = 0;
    ASSERT_TRUE(m.take_polygon(poly, n));
    ASSERT_EQ(n, 4u);
    for (std::size_t i = 0; i < n; ++i) {
        EXPECT_EQ(poly[i].x, corners[i].x);
        EXPECT_EQ(poly[i].y, corners[i].y);
    }
    EXPECT_FALSE(m.take_polygon(poly, n)) << "handed over once";
}

TEST(RegionMarker, DwellPlacesAVertexAtTwoSecondsNotBefore) {
    RegionMarker m;
    m.begin();
    const Point2 p{200, 150};
    // Settles at t = 1000 ms; 1.9 s later nothing, 2.0 s later the vertex.
    EXPECT_EQ(hold(m, p, 1000 * kMs, 2900 * kMs), -1);
    EXPECT_NEAR(m.dwell_progress(), 0.95, 1e-9);
    EXPECT_EQ(m.update(&p, kNone, 3000 * kMs), Event::kVertex);
    ASSERT_EQ(m.vertices().size(), 1u);
    // Holding on places no second vertex.
    EXPECT_EQ(hold(m, p, 3020 * kMs, 9000 * kMs), -1);
    EXPECT_EQ(m.vertices().size(), 1u);
}

TEST(RegionMarker, DriftWithinToleranceKeepsTheDwellAndTheVertexIsWhereItSettled) {
    RegionMarker m({2000, 10, 20});
    m.begin();
    Nanos t = 0;
    Event last = Event::kNone;
    for (int i = 0; t <= 2000 * kMs; ++i, t += 20 * kMs) {
        const Point2 p{50.0 + (i % 2 ? 4 : -4), 80.0};  // 8 px apart, within 10
        last = m.update(&p, kNone, t);
    }
    ASSERT_EQ(last, Event::kVertex);
    EXPECT_EQ(m.vertices()[0].x, 46.0);  // the first (settling) position
    // Moving 11 px restarts the clock.
    RegionMarker n({2000, 10, 20});
    n.begin();
    const Point2 a{0, 0}, b{11, 0};
    EXPECT_EQ(n.update(&a, kNone, 0), Event::kNone);
    EXPECT_EQ(n.update(&b, kNone, 1500 * kMs), Event::kNone);
    EXPECT_EQ(n.update(&b, kNone, 3400 * kMs), Event::kNone);
    EXPECT_EQ(n.update(&b, kNone, 3500 * kMs), Event::kVertex);
}

TEST(RegionMarker, LosingTheToolRestartsTheDwell) {
    RegionMarker m;
    m.begin();
    const Point2 p{10, 10};
    EXPECT_EQ(m.update(&p, kNone, 0), Event::kNone);
    EXPECT_EQ(m.update(nullptr, kNone, 1500 * kMs), Event::kNone);
    EXPECT_EQ(m.update(&p, kNone, 1600 * kMs), Event::kNone);
    EXPECT_EQ(m.update(&p, kNone, 3500 * kMs), Event::kNone);
    EXPECT_EQ(m.update(&p, kNone, 3600 * kMs), Event::kVertex);
}

TEST(RegionMarker, ReturningToTheFirstVertexCloses) {
    RegionMarker m({2000, 10, 20});
    m.begin();
    Nanos t = 0;
    for (const Point2& c : std::vector<Point2>{{100, 100}, {200, 100}, {150, 200}}) {
        ASSERT_GE(hold(m, c, t, t + 3000 * kMs), 0);
        t += 3000 * kMs;
    }
    // 15 px from the first vertex: within close_px, so the dwell closes the outline.
    ASSERT_GE(hold(m, {112, 109}, t, t + 3000 * kMs, Event::kClosed), 0);
    std::array<Point2, RegionMarker::kMaxVertices> poly{};
    std::size_t n = 0;
    ASSERT_TRUE(m.take_polygon(poly, n));
    EXPECT_EQ(n, 3u);
    // With only two vertices, coming back adds a vertex instead.
    RegionMarker two({2000, 10, 20});
    two.begin();
    ASSERT_GE(hold(two, {100, 100}, 0, 3000 * kMs), 0);
    ASSERT_GE(hold(two, {200, 100}, 3000 * kMs, 6000 * kMs), 0);
    ASSERT_GE(hold(two, {105, 100}, 6000 * kMs, 9000 * kMs), 0);
    EXPECT_EQ(two.vertices().size(), 3u);
}

TEST(RegionMarker, LongPressWithFewVerticesCancelsAndIdleIgnoresEverything) {
    RegionMarker m;
    const Point2 p{1, 1};
    std::vector<ControlEvent> ev{press(0)};
    EXPECT_EQ(m.update(&p, ev, 0), Event::kNone) << "not marking";
    m.begin();
    EXPECT_EQ(m.update(&p, ev, 0), Event::kVertex);
    std::vector<ControlEvent> lp{press(kMs, ControlEvent::Kind::kLongPress)};
    EXPECT_EQ(m.update(&p, lp, kMs), Event::kCancelled);
    EXPECT_FALSE(m.marking());
    std::array<Point2, RegionMarker::kMaxVertices> poly{};
    std::size_t n = 0;
    EXPECT_FALSE(m.take_polygon(poly, n));
    // A press without a tool places nothing.
    m.begin();
    EXPECT_EQ(m.update(nullptr, ev, 2 * kMs), Event::kNone);
    EXPECT_TRUE(m.vertices().empty());
}

TEST(RegionMarker, TheSixteenthVertexClosesTheOutline) {
    RegionMarker m;
    m.begin();
    Event e = Event::kNone;
    for (int i = 0; i < 16; ++i) {
        const Point2 p{i * 30.0, (i % 4) * 40.0 + 200};
        std::vector<ControlEvent> ev{press(i * kMs)};
        e = m.update(&p, ev, i * kMs);
    }
    EXPECT_EQ(e, Event::kClosed);
    std::array<Point2, RegionMarker::kMaxVertices> poly{};
    std::size_t n = 0;
    ASSERT_TRUE(m.take_polygon(poly, n));
    EXPECT_EQ(n, 16u);
}
