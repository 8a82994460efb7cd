// UsbHotplug against real USB in the qemu guest: qemu's xHCI controller with its
// USB mouse (0627:0001), driven by xhci-hcd, usbhid and hid-generic, and udevd
// (libusb's udev backend gets its events through udevd, as on the appliance).
// Removal and arrival come from unbinding and binding the xHCI controller. The
// same mouse, through hidraw, is a HidHandle whose reconnect the hotplug drives.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "endotower/hid/hid_handle.hpp"
#include "endotower/usb/usb_hotplug.hpp"

namespace endotower::usb {
namespace {

constexpr std::uint16_t kQemuVid = 0x0627, kMousePid = 0x0001;
const std::string kXhci = "/sys/bus/pci/drivers/xhci_hcd";

template <typename Cond>
bool eventually(Cond cond) {
    for (int i = 0; i < 1000; ++i) {
        if (cond()) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return cond();
}

std::string xhci_address() {
    for (const auto& e : std::filesystem::directory_iterator(kXhci))
        if (e.path().filename().string().rfind("0000:", 0) == 0) return e.path().filename();
    return {};
}

void write_sysfs(const std::string& path, const std::string& value) {
    std::ofstream f(path);
    f << value;
    f.flush();
    ASSERT_TRUE(f) << path;
}

TEST(UsbGuest, HotplugReportsArrivalAndRemovalAndDrivesTheHandle) {
    ASSERT_EQ(std::system("/lib/systemd/systemd-udevd --daemon >/dev/null 2>&1"), 0);
    const std::string pci = xhci_address();
    ASSERT_FALSE(pci.empty()) << "no xHCI controller bound";

    hid::HidHandle handle({kQemuVid, kMousePid, "", 0});
    std::string error;
    ASSERT_TRUE(handle.start(error)) << error;
    ASSERT_TRUE(eventually([&] { return handle.connected(); })) << handle.last_error();

    std::atomic<int> arrived{0}, left{0};
    UsbHotplug hotplug(kQemuVid, kMousePid);
    ASSERT_TRUE(hotplug.start(
        [&](bool a) {
            (a ? arrived : left)++;
            if (a) handle.notify_arrival();
        },
        error))
        << error;
    EXPECT_EQ(arrived.load(), 1);  // already present: reported by the enumeration
    UsbHotplug other(kQemuVid, 0x0002);
    ASSERT_TRUE(other.start(nullptr, error)) << error;
    EXPECT_EQ(other.arrivals(), 0u);

    write_sysfs(kXhci + "/unbind", pci);  // the controller and its mouse go away
    ASSERT_TRUE(eventually([&] { return left.load() == 1; })) << "no removal event";
    ASSERT_TRUE(eventually([&] { return !handle.connected(); }));
    write_sysfs(kXhci + "/bind", pci);
    ASSERT_TRUE(eventually([&] { return arrived.load() == 2; })) << "no arrival event";
    ASSERT_TRUE(eventually([&] { return handle.connected(); })) << handle.last_error();
    EXPECT_EQ(handle.stats().connects, 2u);
    EXPECT_EQ(hotplug.arrivals(), 2u);
    EXPECT_EQ(hotplug.removals(), 1u);
    EXPECT_EQ(other.arrivals() + other.removals(), 0u);  // other VID/PID: nothing
    hotplug.stop();
    handle.stop();
}

}  // namespace
}  // namespace endotower::usb
