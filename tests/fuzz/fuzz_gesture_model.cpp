// libFuzzer target: the gesture model file (board analysis.gestures.model).
#include <cstddef>
#include <cstdint>
#include <string>

#include "endotower/vision/gesture_classifier.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    endotower::vision::GestureClassifier m;
    std::string error;
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    if (m.parse(bytes, "fuzz.yml", error)) {
        if (!m.trained()) __builtin_trap();
        endotower::vision::GestureFeatures f;
        f.valid = true;
        f.compactness = 2, f.roughness = 1.1, f.elongation = 3, f.feret_elongation = 2;
        f.max_changes = 4, f.min_changes = 2;
        const auto r = m.classify(f);
        if (r.label < -1 || r.label >= endotower::vision::kGestureLabelCount) __builtin_trap();
    } else if (error.empty()) {
        __builtin_trap();
    }
    return 0;
}
