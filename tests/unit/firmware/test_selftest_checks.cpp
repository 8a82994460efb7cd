// The selftest's file checks for the gesture stage: the shipped models pass, a corrupt
// file fails naming it and what is wrong, a board without the key skips.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "scratch_dir.hpp"
#include "selftest_checks.hpp"

namespace endotower::firmware {
namespace {

namespace fs = std::filesystem;
const std::string kModels = ENDOTOWER_SOURCE_DIR "/board/sim/models/";

std::string flipped_copy(const std::string& from, const fs::path& to) {
    std::ifstream in(from, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    bytes[bytes.size() / 2] ^= 0x10;
    std::ofstream(to, std::ios::binary) << bytes;
    return to.string();
}

TEST(SelftestChecks, TheGesturePixelModelLoadsOrFailsNamingTheFile) {
    const Check ok = check_gesture_pixel_model(kModels + "gesture_tool_likelihood.bin");
    EXPECT_EQ(ok.name, "gesture pixel model file");
    EXPECT_EQ(ok.result, Check::Result::kPass) << ok.detail;

    const fs::path dir = endotower::test::scratch_dir("selftest_checks");
    const std::string bad = flipped_copy(kModels + "gesture_tool_likelihood.bin", dir / "px.bin");
    const Check corrupt = check_gesture_pixel_model(bad);
    EXPECT_EQ(corrupt.result, Check::Result::kFail);
    EXPECT_NE(corrupt.detail.find(bad), std::string::npos) << corrupt.detail;

    const Check missing = check_gesture_pixel_model((dir / "absent.bin").string());
    EXPECT_EQ(missing.result, Check::Result::kFail);
    EXPECT_NE(missing.detail.find("absent.bin"), std::string::npos) << missing.detail;

    const Check none = check_gesture_pixel_model("");
    EXPECT_EQ(none.result, Check::Result::kSkip);
    EXPECT_NE(none.detail.find("analysis.gestures.tool_model"), std::string::npos);
    fs::remove_all(dir);
}

TEST(SelftestChecks, TheGestureModelLoadsOrFails) {
    EXPECT_EQ(check_gesture_model(kModels + "gestures.yml").result, Check::Result::kPass);
    const fs::path dir = endotower::test::scratch_dir("selftest_checks_model");
    const Check corrupt =
        check_gesture_model(flipped_copy(kModels + "gestures.yml", dir / "gestures.yml"));
    EXPECT_EQ(corrupt.result, Check::Result::kFail);
    EXPECT_NE(corrupt.detail.find("gestures.yml"), std::string::npos) << corrupt.detail;
    fs::remove_all(dir);
}

}  // namespace
}  // namespace endotower::firmware
