#include "endotower/eval/gesture_metrics.hpp"

#include <unordered_map>

namespace endotower::eval {

int gesture_index(const std::string& label) {
    for (int i = 0; i < kGestureCount; ++i)
        if (label == kGestureClasses[i]) return i;
    return -1;
}

std::string gesture_title(int index) {
    std::string s = kGestureClasses[index];
    for (char& c : s)
        if (c == '_') c = ' ';
    return s;
}

std::optional<double> GestureScore::rate(int performed) const {
    int total = 0;
    for (int r = 0; r < kGestureCount; ++r) total += counts[performed][r];
    if (total == 0) return std::nullopt;
    return static_cast<double>(counts[performed][performed]) / total;
}

std::optional<double> GestureScore::overall_rate() const {
    if (trials == 0) return std::nullopt;
    return static_cast<double>(correct_trials) / trials;
}

namespace {

const int kNone = kGestureCount - 1;

int performed_label(const TruthFrame& f) {
    if (f.gesture) return gesture_index(*f.gesture);
    const TruthTool* only = nullptr;
    int visible = 0;
    for (const TruthTool& t : f.tools) {
        if (!t.visible) continue;
        ++visible;
        only = &t;
    }
    if (visible == 1 && !only->gesture.empty()) return gesture_index(only->gesture);
    return kNone;
}

}  // namespace

GestureScore score_gestures(const std::vector<TruthFrame>& truth,
                            const std::vector<AnalysisFrame>& trace) {
    GestureScore s;
    std::unordered_map<std::int64_t, const TraceGesture*> by_frame;
    for (const AnalysisFrame& a : trace)
        if (a.gesture) by_frame[a.frame] = &*a.gesture;
    s.present = !by_frame.empty();
    if (!s.present) return s;
    int trial = -1;           // performed label of the open trial, -1 before the first
    int recognized = kNone;   // first fired label in the open trial
    bool fired = false;
    auto close_trial = [&] {
        if (trial < 0) return;
        ++s.counts[trial][recognized];
        ++s.trials;
        if (trial == recognized) ++s.correct_trials;
    };
    for (const TruthFrame& f : truth) {
        const int performed = performed_label(f);
        if (performed != trial) {
            close_trial();
            trial = performed;
            recognized = kNone;
            fired = false;
        }
        auto it = by_frame.find(f.frame);
        if (it == by_frame.end()) continue;
        const TraceGesture& g = *it->second;
        const int label = g.label ? gesture_index(*g.label) : kNone;
        ++s.frames;
        if (label == performed) ++s.correct_frames;
        if (g.fired && !fired && g.label) {
            fired = true;
            recognized = label;
        }
    }
    close_trial();
    return s;
}

}  // namespace endotower::eval
