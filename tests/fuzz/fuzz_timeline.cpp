// libFuzzer target: the event timeline parser (outside data: a file a user writes).
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "endotower/sim/timeline.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    endotower::sim::Timeline t;
    std::string error;
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    if (endotower::sim::parse_timeline(text, "fuzz", t, error)) {
        // Every accepted entry must be one the grammar allows.
        for (const auto& e : t.entries) {
            if (e.line < 1 || e.frame < 0 || e.offset_ns < 0) __builtin_trap();
            if (e.event.kind == endotower::hal::ControlEvent::Kind::kWheel &&
                (e.event.delta == 0 || e.event.delta < -1000 || e.event.delta > 1000))
                __builtin_trap();
        }
    } else if (error.rfind("fuzz:", 0) != 0) {
        __builtin_trap();  // every error names the file
    }
    return 0;
}
