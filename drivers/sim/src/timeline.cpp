#include "endotower/sim/timeline.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "endotower/system/syscall.hpp"

namespace endotower::sim {

namespace {

using hal::ControlEvent;

constexpr std::int64_t kMaxWheelDelta = 1000;
constexpr int kMaxButton = 7;
constexpr std::size_t kMaxRegionVertices = 16;
// Beyond this many seconds the offset would overflow int64 nanoseconds.
constexpr double kMaxSeconds = 9.0e9;

bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

// Splits one line into whitespace-separated fields, without allocating.
class Fields {
public:
    explicit Fields(std::string_view line) : rest_(line) {}

    // Next field, or an empty view at the end of the line.
    std::string_view next() {
        std::size_t i = 0;
        while (i < rest_.size() && is_space(rest_[i])) ++i;
        std::size_t j = i;
        while (j < rest_.size() && !is_space(rest_[j])) ++j;
        const std::string_view f = rest_.substr(i, j - i);
        rest_.remove_prefix(j);
        return f;
    }

private:
    std::string_view rest_;
};

// The whole field must be an integer (an optional leading '+' is allowed, as in
// "wheel +2"); from_chars alone would accept "12abc" as 12.
bool parse_int(std::string_view s, std::int64_t& out) {
    if (s.size() > 1 && s[0] == '+' && s[1] != '-') s.remove_prefix(1);
    if (s.empty()) return false;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// Seconds as a plain decimal ("1.250", "2", "0.5"); no sign, exponent, inf or nan.
bool parse_seconds(std::string_view s, hal::Nanos& out) {
    if (s.empty()) return false;
    for (char c : s)
        if (!((c >= '0' && c <= '9') || c == '.')) return false;
    double v = 0.0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v, std::chars_format::fixed);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return false;
    if (!std::isfinite(v) || v < 0.0 || v > kMaxSeconds) return false;
    out = static_cast<hal::Nanos>(std::llround(v * 1e9));
    return true;
}

// "x,y": two plain decimals (sign and fraction allowed, no exponent, inf or nan).
bool parse_vertex(std::string_view s, TimelinePoint& out) {
    const std::size_t comma = s.find(',');
    if (comma == std::string_view::npos) return false;
    auto number = [](std::string_view v, double& d) {
        if (v.empty()) return false;
        for (char c : v)
            if (!((c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+')) return false;
        if (v[0] == '+') v.remove_prefix(1);
        const auto r = std::from_chars(v.data(), v.data() + v.size(), d, std::chars_format::fixed);
        return r.ec == std::errc() && r.ptr == v.data() + v.size() && std::isfinite(d) && std::abs(d) <= 1e6;
    };
    return number(s.substr(0, comma), out.x) && number(s.substr(comma + 1), out.y);
}

std::string quoted(std::string_view s) {
    std::string q = "'";
    q += s;
    q += '\'';
    return q;
}

}  // namespace

bool parse_timeline(std::string_view text, std::string_view name, Timeline& out,
                    std::string& error) {
    out.entries.clear();
    int line_no = 0;
    std::string_view rest = text;
    bool more = !rest.empty();
    while (more) {
        ++line_no;
        const std::size_t nl = rest.find('\n');
        std::string_view line = rest.substr(0, nl);
        more = nl != std::string_view::npos;
        rest.remove_prefix(more ? nl + 1 : rest.size());
        // A '#' starts a comment, also after an entry; CR of CRLF files is whitespace.
        if (const std::size_t hash = line.find('#'); hash != std::string_view::npos)
            line = line.substr(0, hash);

        auto fail = [&](const std::string& what) {
            error = std::string(name) + ':' + std::to_string(line_no) + ": " + what;
            out.entries.clear();
            return false;
        };

        Fields fields(line);
        const std::string_view anchor = fields.next();
        if (anchor.empty()) continue;  // blank or comment-only line

        TimelineEntry entry;
        entry.line = line_no;
        const std::string_view value = fields.next();
        if (anchor == "frame") {
            entry.anchor = TimelineEntry::Anchor::kFrame;
            if (value.empty()) return fail("'frame' needs a frame index (non-negative integer)");
            if (!parse_int(value, entry.frame) || entry.frame < 0 || value[0] == '+')
                return fail("frame index " + quoted(value) + " must be a non-negative integer");
        } else if (anchor == "t") {
            entry.anchor = TimelineEntry::Anchor::kTime;
            if (value.empty()) return fail("'t' needs a time in seconds (number >= 0)");
            if (!parse_seconds(value, entry.offset_ns))
                return fail("time " + quoted(value) +
                            " must be a number of seconds >= 0 (like 1.250)");
        } else {
            return fail("unknown anchor " + quoted(anchor) +
                        " (expected 'frame N' or 't SECONDS')");
        }

        const std::string_view kind = fields.next();
        std::string_view arg = fields.next();
        ControlEvent& ev = entry.event;
        if (kind.empty()) {
            return fail("missing event after " + std::string(anchor) + ' ' + std::string(value) +
                        " (expected press, release, wheel or region)");
        } else if (kind == "region") {
            for (; !arg.empty(); arg = fields.next()) {
                // A trailing overlay=KIND names what is anchored (checked by the caller).
                if (arg.substr(0, 8) == "overlay=") {
                    entry.overlay = std::string(arg.substr(8));
                    if (!fields.next().empty())
                        return fail("overlay=KIND must come after the region's vertices");
                    break;
                }
                TimelinePoint v;
                if (!parse_vertex(arg, v))
                    return fail("region vertex " + quoted(arg) + " must be x,y (two numbers)");
                if (entry.region.size() == kMaxRegionVertices)
                    return fail("a region has at most 16 vertices");
                entry.region.push_back(v);
            }
            if (entry.region.size() < 3)
                return fail("a region needs at least 3 vertices \"x1,y1 x2,y2 x3,y3\", got " +
                            std::to_string(entry.region.size()));
        } else if (kind == "press" || kind == "release") {
            ev.kind = kind == "press" ? ControlEvent::Kind::kButtonPress
                                      : ControlEvent::Kind::kButtonRelease;
            ev.button = 0;
            if (!arg.empty()) {
                std::int64_t b = 0;
                if (!parse_int(arg, b) || b < 0 || b > kMaxButton)
                    return fail("button " + quoted(arg) + " must be an integer in 0..7");
                ev.button = static_cast<std::uint8_t>(b);
            }
        } else if (kind == "wheel") {
            ev.kind = ControlEvent::Kind::kWheel;
            if (arg.empty()) return fail("wheel needs a delta (non-zero integer in -1000..1000)");
            std::int64_t d = 0;
            if (!parse_int(arg, d) || d == 0 || d < -kMaxWheelDelta || d > kMaxWheelDelta)
                return fail("wheel delta must be a non-zero integer in -1000..1000, got " +
                            quoted(arg));
            ev.delta = static_cast<std::int16_t>(d);
        } else {
            return fail("unknown event " + quoted(kind) +
                        " (expected press, release, wheel or region)");
        }
        if (const std::string_view extra = fields.next(); !extra.empty())
            return fail("unexpected " + quoted(extra) + " after the event");
        out.entries.push_back(std::move(entry));
    }
    return true;
}

bool load_timeline(const std::string& path, Timeline& out, std::string& error) {
    out.entries.clear();
    struct Closer {
        void operator()(std::FILE* f) const { std::fclose(f); }
    };
    std::unique_ptr<std::FILE, Closer> file(std::fopen(path.c_str(), "rb"));
    if (!file) {
        const int err = errno;  // before anything else can change it
        error = "cannot read timeline: " + system::errno_message("open", path, err);
        return false;
    }
    std::string text;
    char buf[4096];
    for (;;) {
        const std::size_t n = std::fread(buf, 1, sizeof buf, file.get());
        if (n < sizeof buf && std::ferror(file.get())) {
            // fread reports EISDIR for a directory opened by mistake.
            const int err = errno;
            error = "cannot read timeline: " + system::errno_message("read", path, err);
            return false;
        }
        text.append(buf, n);
        if (n < sizeof buf) break;
    }
    return parse_timeline(text, path, out, error);
}

}  // namespace endotower::sim
