// uhid_handle_tool SECONDS: the endotower handle (1209:e770, the unit tests' report
// descriptor) as a uhid device for SECONDS, pressing and releasing its button and
// turning its wheel by one detent every second, for the selftest guest test.
// Prints "ready" once the kernel has started the device.
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "../unit/hid/handle_descriptors.hpp"
#include "uhid_device.hpp"

int main(int argc, char** argv) {
    const int seconds = argc > 1 ? std::atoi(argv[1]) : 60;
    endotower::testing::UhidDevice dev;
    const std::string err = dev.create(endotower::hid::testing::kHandleDescriptor, 0x1209, 0xe770);
    if (!err.empty()) {
        std::fprintf(stderr, "uhid_handle_tool: %s\n", err.c_str());
        return 1;
    }
    std::printf("ready\n");
    std::fflush(stdout);
    for (int i = 0; i < seconds; ++i) {
        const std::uint8_t press[] = {1, 0x01, 0, 0, 0};
        const std::uint8_t release_wheel[] = {1, 0x00, 0, 0, 1};
        dev.input(press);
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        dev.input(release_wheel);
        std::this_thread::sleep_for(std::chrono::milliseconds(700));
    }
    return 0;
}
