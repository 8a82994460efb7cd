#include <gtest/gtest.h>

#include <cstdint>
#include <thread>
#include <vector>

#include "endotower/app/helper_thread.hpp"

namespace endotower::app {
namespace {

// What one job reads and writes: plain (non-atomic) fields, so that a wait() that
// returned before the job finished would show as a wrong value here and as a race
// under ThreadSanitizer.
struct Halves {
    std::vector<std::uint32_t> values;
    std::uint32_t round = 0;
    std::thread::id ran_on;
};

void fill_second_half(void* arg) {
    Halves& h = *static_cast<Halves*>(arg);
    for (std::size_t i = h.values.size() / 2; i < h.values.size(); ++i)
        h.values[i] = h.round * 1000003u + static_cast<std::uint32_t>(i);
    h.ran_on = std::this_thread::get_id();
}

// Each wait() returns once that round's job has run, on the helper, while the caller
// filled the other half; the rounds do not mix.
TEST(HelperThread, EachWaitSeesItsJobDone) {
    HelperThread helper;
    Halves h;
    h.values.assign(4096, 0);
    for (std::uint32_t round = 1; round <= 500; ++round) {
        h.round = round;
        helper.post(fill_second_half, &h);
        for (std::size_t i = 0; i < h.values.size() / 2; ++i)
            h.values[i] = round * 1000003u + static_cast<std::uint32_t>(i);
        helper.wait();
        ASSERT_NE(h.ran_on, std::this_thread::get_id());
        for (std::size_t i = 0; i < h.values.size(); ++i)
            ASSERT_EQ(h.values[i], round * 1000003u + i) << "round " << round << ", value " << i;
    }
}

// wait() with nothing posted returns at once; a helper that never ran a job, or whose
// last job was waited for, is joined by its destructor.
TEST(HelperThread, IdleHelpersStopCleanly) {
    { HelperThread unused; }
    HelperThread helper;
    helper.wait();
    Halves h;
    h.values.assign(2, 0);
    h.round = 7;
    helper.post(fill_second_half, &h);
    helper.wait();
    helper.wait();  // a second wait for the same job
    EXPECT_EQ(h.values[1], 7u * 1000003u + 1u);
    EXPECT_EQ(h.values[0], 0u);
}

}  // namespace
}  // namespace endotower::app
