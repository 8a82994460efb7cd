#include "endotower/hid/report_descriptor.hpp"

namespace endotower::hid {

namespace {

constexpr std::uint16_t kPageGenericDesktop = 0x01;
constexpr std::uint16_t kPageButton = 0x09;
constexpr std::uint16_t kUsageWheel = 0x38;
constexpr int kMaxUsages = 64;    // local usages kept per main item
constexpr int kMaxPushDepth = 8;  // Push/Pop nesting
constexpr int kMaxCollectionDepth = 16;
constexpr std::uint32_t kMaxReportBits = kMaxReportBytes * 8;

struct Globals {
    std::uint16_t usage_page = 0;
    std::int32_t logical_min = 0;
    std::uint32_t report_size = 0;
    std::uint32_t report_count = 0;
    std::uint8_t report_id = 0;
};

struct Locals {
    std::array<std::uint32_t, kMaxUsages> usages{};  // page << 16 | id
    int count = 0;
    std::uint32_t min = 0, max = 0;
    bool has_range = false;
    // The usage of field i: the list (last one repeats) or the range (clamped).
    std::uint32_t usage(std::uint32_t i) const {
        if (has_range) return max - min >= i ? min + i : max;
        if (count == 0) return 0;
        return usages[i < static_cast<std::uint32_t>(count) ? i : count - 1];
    }
};

std::uint32_t unsigned_value(const std::uint8_t* p, int size) {
    std::uint32_t v = 0;
    for (int i = 0; i < size; ++i) v |= static_cast<std::uint32_t>(p[i]) << (8 * i);
    return v;
}

std::int32_t signed_value(const std::uint8_t* p, int size) {
    const std::uint32_t v = unsigned_value(p, size);
    if (size == 1) return static_cast<std::int8_t>(v);
    if (size == 2) return static_cast<std::int16_t>(v);
    return static_cast<std::int32_t>(v);
}

// Extended usages (4 bytes) carry their own page; shorter ones take the current page.
std::uint32_t full_usage(std::uint32_t v, int size, std::uint16_t page) {
    return size == 4 ? v : (static_cast<std::uint32_t>(page) << 16) | (v & 0xffff);
}

}  // namespace

int HandleLayout::button_count() const {
    int n = 0;
    for (const auto& b : buttons) n += b.present ? 1 : 0;
    return n;
}

bool parse_report_descriptor(std::span<const std::uint8_t> d, HandleLayout& out,
                             std::string& error) {
    HandleLayout layout;
    Globals g;
    std::array<Globals, kMaxPushDepth> stack{};
    int depth = 0, collections = 0;
    Locals l;
    std::array<std::uint32_t, 256> input_bits{};
    bool saw_id = false;
    const auto fail = [&](std::size_t at, const char* what) {
        error = "HID report descriptor, byte " + std::to_string(at) + ": " + what;
        return false;
    };

    std::size_t i = 0;
    while (i < d.size()) {
        const std::size_t at = i;
        const std::uint8_t prefix = d[i++];
        if (prefix == 0xfe) {  // long item: size byte, tag byte, data; none is defined
            if (i + 2 > d.size() || i + 2 + d[i] > d.size()) return fail(at, "truncated long item");
            i += 2 + d[i];
            continue;
        }
        const int size = (prefix & 3) == 3 ? 4 : prefix & 3;
        if (i + size > d.size()) return fail(at, "item runs past the end");
        const std::uint8_t* data = d.data() + i;
        i += size;
        const std::uint32_t uv = unsigned_value(data, size);
        const int type = (prefix >> 2) & 3, tag = prefix >> 4;
        if (type == 0) {       // main
            if (tag == 0x8) {  // Input
                if (g.report_size == 0 || g.report_size > 32)
                    return fail(at, "Input with report size 0 or > 32");
                if (g.report_count > kMaxReportBits)
                    return fail(at, "Input report count too large");
                std::uint32_t& bits = input_bits[g.report_id];
                const bool constant = uv & 1, variable = uv & 2, relative = uv & 4;
                for (std::uint32_t f = 0; f < g.report_count && !constant && variable; ++f) {
                    const std::uint32_t u = l.usage(f);
                    const std::uint32_t off = bits + f * g.report_size;
                    if (off + g.report_size > kMaxReportBits) break;
                    ReportField field{true,
                                      g.report_id,
                                      static_cast<std::uint16_t>(off),
                                      static_cast<std::uint8_t>(g.report_size),
                                      g.logical_min < 0,
                                      relative};
                    const std::uint16_t page = u >> 16, id = u & 0xffff;
                    if (page == kPageButton && id >= 1 && id <= kMaxButtons &&
                        !layout.buttons[id - 1].present)
                        layout.buttons[id - 1] = field;
                    else if (page == kPageGenericDesktop && id == kUsageWheel &&
                             !layout.wheel.present)
                        layout.wheel = field;
                }
                bits += g.report_size * g.report_count;
                if (bits > kMaxReportBits) return fail(at, "input report longer than 64 bytes");
            } else if (tag == 0xa) {
                if (++collections > kMaxCollectionDepth)
                    return fail(at, "collections nested too deep");
            } else if (tag == 0xc) {
                if (--collections < 0) return fail(at, "End Collection without Collection");
            } else if (tag != 0x9 && tag != 0xb) {
                return fail(at, "unknown main item");
            }
            l = Locals{};
        } else if (type == 1) {  // global
            switch (tag) {
                case 0x0:
                    g.usage_page = static_cast<std::uint16_t>(uv);
                    break;
                case 0x1:
                    g.logical_min = signed_value(data, size);
                    break;
                case 0x7:
                    g.report_size = uv;
                    break;
                case 0x8:
                    if (uv == 0 || uv > 255) return fail(at, "report ID must be 1..255");
                    g.report_id = static_cast<std::uint8_t>(uv);
                    saw_id = true;
                    break;
                case 0x9:
                    g.report_count = uv;
                    break;
                case 0xa:
                    if (depth == kMaxPushDepth) return fail(at, "Push nested too deep");
                    stack[depth++] = g;
                    break;
                case 0xb:
                    if (depth == 0) return fail(at, "Pop without Push");
                    g = stack[--depth];
                    break;
                default:
                    break;  // logical max, physical range, unit: not needed
            }
        } else if (type == 2) {  // local
            if (tag == 0x0 && l.count < kMaxUsages)
                l.usages[l.count++] = full_usage(uv, size, g.usage_page);
            if (tag == 0x1) l.min = full_usage(uv, size, g.usage_page), l.has_range = true;
            if (tag == 0x2) l.max = full_usage(uv, size, g.usage_page), l.has_range = true;
        } else {
            return fail(at, "reserved item type");
        }
    }
    if (collections != 0) return fail(d.size(), "unclosed collection");
    if (saw_id && input_bits[0] != 0)
        return fail(d.size(), "input fields before the first report ID");
    if (layout.button_count() == 0 && !layout.wheel.present)
        return fail(d.size(),
                    "no button (page 0x09) and no wheel (page 0x01 usage 0x38) input field");
    layout.numbered = saw_id;
    for (std::size_t id = 0; id < input_bits.size(); ++id)
        layout.input_bytes[id] = static_cast<std::uint16_t>((input_bits[id] + 7) / 8);
    out = layout;
    return true;
}

const char* to_string(ReportStatus s) {
    switch (s) {
        case ReportStatus::kOk:
            return "ok";
        case ReportStatus::kEmpty:
            return "empty";
        case ReportStatus::kUnknownId:
            return "unknown report ID";
        case ReportStatus::kShort:
            return "short";
        case ReportStatus::kOversized:
            return "oversized";
    }
    return "?";
}

namespace {
std::uint32_t extract(const std::uint8_t* p, const ReportField& f) {
    std::uint64_t v = 0;
    const int first = f.bit_offset / 8, last = (f.bit_offset + f.bit_size - 1) / 8;
    for (int b = last; b >= first; --b) v = (v << 8) | p[b];
    v >>= f.bit_offset % 8;
    return static_cast<std::uint32_t>(v & ((std::uint64_t{1} << f.bit_size) - 1));
}
}  // namespace

ReportStatus ReportDecoder::decode(std::span<const std::uint8_t> report, hal::Nanos time_ns,
                                   std::array<hal::ControlEvent, kMaxButtons + 1>& out,
                                   int& count) {
    count = 0;
    if (report.empty()) return ReportStatus::kEmpty;
    const std::uint8_t id = layout_.numbered ? report[0] : 0;
    const std::size_t header = layout_.numbered ? 1 : 0;
    const std::size_t expected = layout_.input_bytes[id];
    if (expected == 0) return ReportStatus::kUnknownId;
    if (report.size() - header < expected) return ReportStatus::kShort;
    if (report.size() - header > expected) return ReportStatus::kOversized;
    const std::uint8_t* p = report.data() + header;

    std::uint32_t buttons = buttons_;
    for (int b = 0; b < kMaxButtons; ++b) {
        const ReportField& f = layout_.buttons[b];
        if (!f.present || f.report_id != id) continue;
        const bool down = extract(p, f) != 0;
        if (down == ((buttons >> b) & 1)) continue;
        buttons ^= 1u << b;
        out[count++] = {
            down ? hal::ControlEvent::Kind::kButtonPress : hal::ControlEvent::Kind::kButtonRelease,
            static_cast<std::uint8_t>(b), 0, time_ns};
    }
    buttons_ = buttons;
    const ReportField& w = layout_.wheel;
    if (w.present && w.report_id == id) {
        std::int64_t v = extract(p, w);
        if (w.is_signed && (v >> (w.bit_size - 1)) & 1) v -= std::int64_t{1} << w.bit_size;
        // An absolute wheel would need its previous position; handles send relative detents.
        if (v != 0 && w.relative) {
            const std::int64_t clamped = v > 32767 ? 32767 : (v < -32768 ? -32768 : v);
            out[count++] = {hal::ControlEvent::Kind::kWheel, 0, static_cast<std::int16_t>(clamped),
                            time_ns};
        }
    }
    return ReportStatus::kOk;
}

int ReportDecoder::release_all(hal::Nanos time_ns,
                               std::array<hal::ControlEvent, kMaxButtons + 1>& out) {
    int count = 0;
    for (int b = 0; b < kMaxButtons; ++b)
        if ((buttons_ >> b) & 1)
            out[count++] = {hal::ControlEvent::Kind::kButtonRelease, static_cast<std::uint8_t>(b),
                            0, time_ns};
    buttons_ = 0;
    return count;
}

}  // namespace endotower::hid
