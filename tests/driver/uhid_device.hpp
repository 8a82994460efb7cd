// UhidDevice: a virtual HID device created through /dev/uhid (the kernel's uhid
// driver), for the guest tests: the handle under test finds it through hidraw like
// a real USB handle. Test helper; Linux only; aborts the test on failure.
#pragma once

#include <fcntl.h>
#include <linux/uhid.h>
#include <poll.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <span>
#include <string>

namespace endotower::testing {

class UhidDevice {
public:
    ~UhidDevice() { destroy(); }

    // Creates the device (bus USB) and waits for the kernel's UHID_START.
    // Empty string on success, else what failed.
    std::string create(std::span<const std::uint8_t> descriptor, std::uint16_t vid,
                       std::uint16_t pid) {
        fd_ = ::open("/dev/uhid", O_RDWR | O_CLOEXEC);
        if (fd_ < 0) return std::string("open(/dev/uhid): ") + std::strerror(errno);
        uhid_event ev{};
        ev.type = UHID_CREATE2;
        std::snprintf(reinterpret_cast<char*>(ev.u.create2.name), sizeof ev.u.create2.name,
                      "endotower test handle");
        std::memcpy(ev.u.create2.rd_data, descriptor.data(), descriptor.size());
        ev.u.create2.rd_size = static_cast<std::uint16_t>(descriptor.size());
        ev.u.create2.bus = 0x03;  // BUS_USB
        ev.u.create2.vendor = vid;
        ev.u.create2.product = pid;
        if (!send(ev))
            return std::string("write(/dev/uhid, UHID_CREATE2): ") + std::strerror(errno);
        for (;;) {
            pollfd p{fd_, POLLIN, 0};
            if (::poll(&p, 1, 10000) <= 0) return "no UHID_START within 10 s";
            uhid_event in{};
            if (::read(fd_, &in, sizeof in) <= 0)
                return std::string("read(/dev/uhid): ") + std::strerror(errno);
            if (in.type == UHID_START) return {};
        }
    }

    // Sends one input report (report-ID byte first when the descriptor numbers them).
    bool input(std::span<const std::uint8_t> report) {
        uhid_event ev{};
        ev.type = UHID_INPUT2;
        std::memcpy(ev.u.input2.data, report.data(), report.size());
        ev.u.input2.size = static_cast<std::uint16_t>(report.size());
        return send(ev);
    }

    // Removes the device (like pulling the USB cable).
    void destroy() {
        if (fd_ < 0) return;
        uhid_event ev{};
        ev.type = UHID_DESTROY;
        send(ev);
        ::close(fd_);
        fd_ = -1;
    }

private:
    bool send(const uhid_event& ev) {
        return ::write(fd_, &ev, sizeof ev) == static_cast<ssize_t>(sizeof ev);
    }
    int fd_ = -1;
};

}  // namespace endotower::testing
