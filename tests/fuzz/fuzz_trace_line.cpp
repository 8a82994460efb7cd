// libFuzzer target: one trace line (outside data for `eval` and tools).
#include <cstddef>
#include <cstdint>
#include <string>

#include "endotower/app/trace_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    endotower::app::TraceRecord r;
    std::string error;
    const std::string line(reinterpret_cast<const char*>(data), size);
    if (!endotower::app::parse_trace_line(line, r, error) && error.empty()) __builtin_trap();
    return 0;
}
