// GestureStage: tool-gesture recognition on the analysis path (book ch. 3).
//
// Per frame: GestureSegmenter finds up to two tool tips; each is classified
// (GestureClassifier). One region with a gesture = the frame's gesture (a single tool,
// or two crossing tools: cross / triangle / double triangle); two are two single-tool
// calls (fig. 3.21) and the frame's label is null (each tool's own is listed), except
// that a region with a two-tool gesture holds both tools, so its gesture is the frame's
// whatever another region shows (`crossing_is_the_frames`, default on: a glint patch at
// the rim read as scissors beside a cross; docs/gestures.md).
// A label below `min_confidence` (0.5; the open grasper's own bar
// `open_grasper_min_confidence`, 0.4: it commands nothing on its own) counts as none; so
// does a region whose tip window no arm leaves (GestureBlob::arms 0: the window holds the
// whole region, so its shape is not the jaws'; two tools at rest against each other read
// as a cross), and a two-tool gesture (cross, triangle, double triangle) in a window only
// one arm leaves (crossing jaws leave it as two shafts; one is a tool resting against
// the other).
// Where a region enters twice and no arm leaves its window, the arms are counted on the
// window of the thinner entry's shaft instead (`thin_window_arms`, default on: a 10 mm
// grasper crossing a 5 mm tool near the scope; GestureBlob::thin_arms).
// Two regions each with a single-tool gesture: with a pointer (set_pointer: the tip the
// surgeon points with, the SCI's cursor) the frame's gesture is the region's whose tip
// lies within `pointer_fraction` (0.1) x frame width of it and nearer than the other's
// (a glint patch at the rim read as a closed grasper beside the pointing tool's open
// one; docs/gestures.md "The pointing tool's gesture"); without one, or with neither
// near it, none.
// GestureHold: a gesture fires once, when the same label has been held for
// `hold_ms` (1000) with its tip within `still_fraction` (0.03) x frame width of where
// the hold began, on a frame that shows it; moving starts a new hold. Another label
// (or none) for at most `dropout_ms` (200) is a misclassified frame or two and the hold
// goes on; longer, and the new label's hold is taken to have begun where it first
// appeared (so a real change is not delayed). A hold counts only while at least
// `min_support` (0.5) of its frames show its label: below that the frame reports no
// gesture and nothing fires (a label that flickers in one frame of four, each gap
// under `dropout_ms`, is not held; docs/gestures.md "Support"). Times are the frames'
// capture times (exact on the virtual clock).
// Trace member, every frame:
//   "gesture": {"label": string|null, "confidence", "held_ms", "fired",
//               "tools": [{"label", "read", "confidence", "entries", "arms",
//                          "thin_arms", "tip_px": [x, y]}]}
//   (per region, "read" is the network's label before the rules above, null for "not a
//   tool"; "label" is "read" or null; "confidence" is the read label's output)
// Overlay: a square at each classified tip, filled when the gesture has fired.
// Borrows the segmenter and the classifier. current(): this frame's gesture for the
// stages after it in the chain (the SCI).
#pragma once

#include <array>
#include <functional>

#include "endotower/app/analysis_stage.hpp"
#include "endotower/vision/gesture_classifier.hpp"
#include "endotower/vision/gesture_segmenter.hpp"

namespace endotower::vision {

struct GestureHoldParams {
    double hold_ms = 1000.0;
    double still_fraction = 0.03;
    double dropout_ms = 200.0;
    double min_support = 0.5;
};

class GestureHold {
public:
    struct State {
        int label = -1;  // -1: none
        double held_ms = 0;
        bool fired = false;  // true on the one frame the hold reaches hold_ms
        Point2 where;        // where the held gesture was last seen (its tip)
    };
    explicit GestureHold(GestureHoldParams params = {}) : params_(params) {}
    // `still_px`: the tolerance in the caller's pixels (still_fraction x width).
    State update(int label, Point2 where, hal::Nanos t_ns, double still_px);

private:
    GestureHoldParams params_;
    int label_ = -1;
    Point2 anchor_, seen_;                     // where the hold began, where it was last seen
    hal::Nanos start_ns_ = 0, agreed_ns_ = 0;  // the hold's start, its last agreeing frame
    bool fired_ = false;
    static constexpr int kNoPending = -2;  // (-1 is a run of frames with no gesture)
    int pending_ = kNoPending;             // the other label seen since the last agreeing frame
    Point2 pending_anchor_;
    hal::Nanos pending_ns_ = 0, pending_seen_ns_ = 0;  // its first and last frame
    int frames_ = 0, agreed_ = 0;                      // the hold's frames, those agreeing
    int pending_frames_ = 0, pending_agreed_ = 0;      // the same for the pending label
};

struct GestureStageParams {
    GestureHoldParams hold;
    double min_confidence = 0.5;
    // The open grasper commands nothing on its own: it selects an item of a menu already
    // open, and the selection executes only after a loop. A doubtful open grasper costs
    // a select to deny; a doubtful scissors or cross could open the interface.
    double open_grasper_min_confidence = 0.4;
    bool crossing_is_the_frames = true;  // a two-tool gesture outranks other regions
    bool thin_window_arms = true;        // no arm: count them in the thinner shaft's window
    double pointer_fraction = 0.1;       // two single-tool calls: the one at the pointer
};

// One frame's gesture: label -1 = none; tip where the gesture's region is (px);
// touching: some region enters the image twice (two tools against each other), whatever
// it reads as; dropout: the held label is not this frame's own (GestureHold's dropout).
struct GestureFrame {
    int label = -1;
    double confidence = 0, held_ms = 0;
    bool fired = false;
    Point2 tip;
    bool touching = false;
    bool dropout = false;
};

class GestureStage final : public app::AnalysisStage {
public:
    GestureStage(GestureSegmenter& segmenter, const GestureClassifier& classifier,
                 GestureStageParams params = {})
        : segmenter_(segmenter), classifier_(classifier), params_(params), hold_(params.hold) {}
    std::string_view name() const override { return "gestures"; }
    void configure(const hal::FrameFormat& format) override;
    void process(app::AnalysisContext& ctx) override;
    const GestureFrame& current() const { return current_; }
    // `pointer` gives this frame's pointing tip (false: none); called once per frame with
    // two single-tool calls. Its captures must outlive the stage.
    void set_pointer(std::function<bool(Point2&)> pointer) { pointer_ = std::move(pointer); }

private:
    GestureFrame current_;
    GestureSegmenter& segmenter_;
    const GestureClassifier& classifier_;
    GestureStageParams params_;
    GestureHold hold_;
    std::function<bool(Point2&)> pointer_;
    std::array<GestureBlob, GestureSegmenter::kMaxBlobs> blobs_{};
    double still_px_ = 20, pointer_px_ = 64;
    int box_ = 10;
};

}  // namespace endotower::vision
