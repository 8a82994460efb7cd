// Test helper: a gesture model file (GestureClassifier::serialise()'s bytes) with its
// body edited and signed again the way serialise() signs (FNV-1a with the project's
// offset basis, gesture_classifier.hpp), so the edit reaches the parser's checks instead
// of failing the checksum.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace endotower::test {

// `model` with the first `from` replaced by `to` (unchanged when `from` is absent:
// `replaced` says which), signed again.
inline std::string edited_gesture_model(const std::string& model, const std::string& from,
                                        const std::string& to, bool* replaced = nullptr) {
    std::string body = model.substr(0, model.size() - 23);  // without "fnv1a <16 hex>\n"
    const std::size_t at = body.find(from);
    if (replaced != nullptr) *replaced = at != std::string::npos;
    if (at != std::string::npos) body.replace(at, from.size(), to);
    std::uint64_t h = 1469598103934665603ull;
    for (char ch : body) h = (h ^ static_cast<std::uint8_t>(ch)) * 1099511628211ull;
    char tail[32];
    std::snprintf(tail, sizeof tail, "fnv1a %016llx\n", static_cast<unsigned long long>(h));
    return body + tail;
}

}  // namespace endotower::test
