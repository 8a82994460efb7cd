// Gesture recognition scores in the layout of the book's table 3.3.
//
// Performed label per frame: the truth's two-tool `gesture` when set; else, with
// exactly one visible tool, that tool's `gesture`; else "none".
// Trials: maximal runs of consecutive frames with the same performed label. The
// recognized label of a trial is the label of the first trace frame in it whose
// gesture `fired` is true, "none" if none fired (a "none" trial that fires is a
// false trigger). Frame accuracy: frames whose trace label (null = "none") equals
// the performed label, over frames whose trace line has a `gesture` member.
// Present only when at least one trace line has a `gesture` member.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "endotower/eval/analysis_trace.hpp"
#include "endotower/eval/truth.hpp"

namespace endotower::eval {

constexpr int kGestureCount = 8;
inline constexpr std::array<const char*, kGestureCount> kGestureClasses = {
    "open_grasper", "closed_grasper", "open_scissors", "closed_scissors",
    "cross",        "triangle",       "double_triangle", "none"};
// Index in kGestureClasses, -1 if unknown.
int gesture_index(const std::string& label);
// "open grasper" etc., as the book's table prints it.
std::string gesture_title(int index);

struct GestureScore {
    bool present = false;
    std::array<std::array<int, kGestureCount>, kGestureCount> counts{};  // [performed][recognized]
    int trials = 0, correct_trials = 0;
    int frames = 0, correct_frames = 0;
    // Recognition rate of a performed class: diagonal / row total; nullopt without trials.
    std::optional<double> rate(int performed) const;
    std::optional<double> overall_rate() const;
};

GestureScore score_gestures(const std::vector<TruthFrame>& truth,
                            const std::vector<AnalysisFrame>& trace);

}  // namespace endotower::eval
