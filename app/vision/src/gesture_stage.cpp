#include "endotower/vision/gesture_stage.hpp"

#include <algorithm>
#include <cmath>

namespace endotower::vision {

GestureHold::State GestureHold::update(int label, Point2 where, hal::Nanos t_ns, double still_px) {
    const auto near = [still_px](Point2 a, Point2 b) {
        return std::hypot(a.x - b.x, a.y - b.y) <= still_px;
    };
    const auto ms = [](hal::Nanos d) { return static_cast<double>(d) / 1e6; };
    // A new hold; `frames` of it already seen (a pending label's run), `agreed` of them
    // showing it.
    const auto restart = [&](int l, Point2 at, hal::Nanos since, int frames, int agreed) {
        label_ = l, anchor_ = seen_ = at, start_ns_ = since, agreed_ns_ = t_ns, fired_ = false;
        pending_ = kNoPending, frames_ = frames, agreed_ = agreed;
    };
    if (label == label_ && label >= 0) {
        if (near(where, anchor_))
            agreed_ns_ = t_ns, seen_ = where, pending_ = kNoPending, ++frames_, ++agreed_;
        else
            restart(label, where, t_ns, 1, 1);  // moved: a new hold
    } else if (label_ < 0) {
        restart(label, where, t_ns, 1, 1);
    } else {
        // Another label (or none): the hold goes on for dropout_ms. The new label's hold
        // dates from its first frame, through frames of no gesture of its own: one such
        // frame in the new label's first 200 ms no longer restarts it; a third label
        // does (docs/gestures.md, "A new label's dropouts").
        ++frames_;
        if (pending_ != kNoPending && label == pending_ &&
            (label < 0 || near(where, pending_anchor_))) {
            pending_seen_ns_ = t_ns, ++pending_frames_, ++pending_agreed_;
        } else if (pending_ >= 0 && label < 0 &&
                   ms(t_ns - pending_seen_ns_) <= params_.dropout_ms) {
            ++pending_frames_;  // a frame with no gesture inside the new label's run
        } else {
            pending_ = label, pending_anchor_ = where, pending_ns_ = pending_seen_ns_ = t_ns;
            pending_frames_ = pending_agreed_ = 1;
        }
        if (ms(t_ns - agreed_ns_) > params_.dropout_ms)
            restart(pending_, pending_anchor_, pending_ns_, pending_frames_, pending_agreed_);
    }
    State s;
    // Not held while fewer than min_support of its frames show it.
    if (label_ < 0 || agreed_ < params_.min_support * frames_) return s;
    s.label = label_;
    s.where = seen_;
    s.held_ms = static_cast<double>(t_ns - start_ns_) / 1e6;
    // It fires on a frame that shows it: a hold whose time runs out inside a dropout
    // waits for its label to come back, and fires not at all if the tools have parted
    // (surgery_motion seed 81: a crossing read as a cross for 24 frames, then two tools
    // again, "fired" 1.0 s after it began, two frames after it was last seen).
    if (!fired_ && s.held_ms >= params_.hold_ms && label == label_) s.fired = fired_ = true;
    return s;
}

void GestureStage::configure(const hal::FrameFormat& format) {
    segmenter_.configure(format);
    still_px_ = params_.hold.still_fraction * format.width;
    pointer_px_ = params_.pointer_fraction * format.width;
    box_ = std::max(6, format.height / 60);
}

void GestureStage::process(app::AnalysisContext& ctx) {
    const std::size_t n =
        segmenter_.segment(ctx.frame, std::span<GestureBlob, GestureSegmenter::kMaxBlobs>(blobs_));
    std::array<GestureResult, GestureSegmenter::kMaxBlobs> results{};
    std::array<int, GestureSegmenter::kMaxBlobs> read{};  // the network's, before the rules
    for (std::size_t i = 0; i < n; ++i) {
        results[i] = classifier_.classify(blobs_[i].features, blobs_[i].entries);
        read[i] = results[i].label;
        // A tip window that no arm leaves holds the whole region, not jaws: a thick tool
        // near the scope widened it past the picture (docs/gestures.md, "No arm"). Two
        // tools whose jaws cross leave the window as two shafts; one arm is a tool
        // resting against the other, not a two-tool gesture ("One arm").
        // A 10 mm grasper near the scope widens the window past a crossing with a 5 mm
        // tool; the thinner shaft's window tells jaws crossing from the tools' bodies
        // (docs/gestures.md, "The thinner shaft's arms").
        int arms = blobs_[i].arms;
        if (arms == 0 && blobs_[i].entries == 2 && params_.thin_window_arms)
            arms = blobs_[i].thin_arms;
        const double bar = results[i].label == kOpenGrasperLabel
                               ? params_.open_grasper_min_confidence
                               : params_.min_confidence;
        if (results[i].confidence < bar || arms == 0 ||
            (two_tool_gesture(results[i].label) && arms < 2))
            results[i].label = -1;
    }
    // One region with a gesture: it is the frame's; two: two single-tool calls. A region
    // with a two-tool gesture holds both of the surgeon's tools, so what another region
    // shows is not one of them (a glint patch at the rim read as scissors; docs/gestures.md,
    // "A crossing and a third region").
    std::size_t gestures = 0, which = 0, crossings = 0, crossing = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (results[i].label >= 0) ++gestures, which = i;
        if (two_tool_gesture(results[i].label)) ++crossings, crossing = i;
    }
    if (crossings == 1 && params_.crossing_is_the_frames) gestures = 1, which = crossing;
    // Two single-tool calls: the pointing tool's is the one the surgeon makes; the other
    // is the idle tool's or tissue's (docs/gestures.md, "The pointing tool's gesture").
    Point2 at;
    if (gestures == 2 && crossings == 0 && pointer_ && pointer_(at)) {
        std::array<double, GestureSegmenter::kMaxBlobs> d{};
        for (std::size_t i = 0; i < n; ++i)
            d[i] = std::hypot(blobs_[i].tip.x - at.x, blobs_[i].tip.y - at.y);
        const std::size_t near = d[1] < d[0] ? 1 : 0;
        if (d[near] <= pointer_px_ && d[near] < d[1 - near]) gestures = 1, which = near;
    }
    const bool one = gestures == 1;
    const GestureHold::State s =
        hold_.update(one ? results[which].label : -1, one ? blobs_[which].tip : Point2{},
                     ctx.frame.capture_ns, still_px_);
    // Through a dropout the held gesture stays where it was last seen.
    const bool seen = one && results[which].label == s.label;
    bool touching = false;
    for (std::size_t i = 0; i < n; ++i) touching = touching || blobs_[i].entries >= 2;
    current_ = {s.label,
                one ? results[which].confidence : 0.0,
                s.held_ms,
                s.fired,
                seen           ? blobs_[which].tip
                : s.label >= 0 ? s.where
                               : Point2{},
                touching,
                s.label >= 0 && !seen};

    ctx.trace.begin_object("gesture");
    if (s.label >= 0)
        ctx.trace.field("label", kGestureLabels[s.label]);
    else
        ctx.trace.null_field("label");
    ctx.trace.field("confidence", one ? results[which].confidence : 0.0)
        .field("held_ms", s.held_ms)
        .field("fired", s.fired)
        .begin_array("tools");
    for (std::size_t i = 0; i < n; ++i) {
        ctx.trace.begin_object();
        if (results[i].label >= 0)
            ctx.trace.field("label", kGestureLabels[results[i].label]);
        else
            ctx.trace.null_field("label");
        if (read[i] >= 0)
            ctx.trace.field("read", kGestureLabels[read[i]]);
        else
            ctx.trace.null_field("read");
        ctx.trace.field("confidence", results[i].confidence)
            .field("entries", blobs_[i].entries)
            .field("arms", blobs_[i].arms)
            .field("thin_arms", blobs_[i].thin_arms)
            .begin_array("tip_px")
            .value(blobs_[i].tip.x)
            .value(blobs_[i].tip.y)
            .end_array()
            .end_object();
    }
    ctx.trace.end_array().end_object();

    // A square at each classified tip; filled once the gesture is held long enough.
    const bool held = one && s.held_ms >= params_.hold.hold_ms;
    for (std::size_t i = 0; i < n; ++i) {
        if (results[i].label < 0) continue;
        const int x = static_cast<int>(std::lround(blobs_[i].tip.x)) - box_ / 2;
        const int y = static_cast<int>(std::lround(blobs_[i].tip.y)) - box_ / 2;
        const app::Rgba c{255, static_cast<std::uint8_t>(60 + 25 * results[i].label), 40, 220};
        if (held) {
            ctx.overlay.fill({x, y, box_, box_}, c);
        } else {
            const int t = std::max(2, box_ / 5);
            ctx.overlay.fill({x, y, box_, t}, c);
            ctx.overlay.fill({x, y + box_ - t, box_, t}, c);
            ctx.overlay.fill({x, y, t, box_}, c);
            ctx.overlay.fill({x + box_ - t, y, t, box_}, c);
        }
    }
}

}  // namespace endotower::vision
