// libFuzzer target: the board file (YAML), through the same load path the firmware
// uses: the bytes are written to a file, then loaded.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "board_config.hpp"
#include "fuzz_scratch_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const endotower::fuzz::ScratchFile scratch("endotower_fuzz_board_", ".yaml");
    const std::string& path = scratch.path();
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) return 0;
    std::fwrite(data, 1, size, f);
    std::fclose(f);
    endotower::firmware::BoardConfig board;
    std::string error;
    if (!endotower::firmware::load_board(path, board, error) && error.rfind(path, 0) != 0)
        __builtin_trap();  // every error names the file
    return 0;
}
