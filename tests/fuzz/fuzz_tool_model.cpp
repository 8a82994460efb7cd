// libFuzzer target: the tool likelihood model file (board analysis.tool_model).
#include <cstddef>
#include <cstdint>
#include <string>

#include "endotower/vision/tool_likelihood.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    endotower::vision::ToolLikelihood m;
    std::string error;
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    if (m.parse(bytes, "fuzz.bin", error)) {
        if (!m.trained()) __builtin_trap();
        volatile int sum = m.probability(0, 0, 0) + m.probability(255, 255, 255) + m.probability(1, 2, 3);
        (void)sum;
    } else if (error.empty()) {
        __builtin_trap();
    }
    return 0;
}
