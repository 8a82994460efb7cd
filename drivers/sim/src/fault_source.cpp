#include "endotower/sim/fault_source.hpp"

#include <algorithm>
#include <cstring>

namespace endotower::sim {

namespace {

using Kind = CaptureFault::Kind;

bool drops_frames(Kind k) {
    return k == Kind::kStall || k == Kind::kDisappear;
}

// BT.601 studio-swing luma and chroma of one BGR pixel, integer arithmetic.
std::uint8_t luma(const std::uint8_t* bgr) {
    return static_cast<std::uint8_t>((66 * bgr[2] + 129 * bgr[1] + 25 * bgr[0] + 128) / 256 + 16);
}
std::uint8_t chroma_u(const std::uint8_t* bgr) {
    return static_cast<std::uint8_t>((-38 * bgr[2] - 74 * bgr[1] + 112 * bgr[0] + 128) / 256 + 128);
}
std::uint8_t chroma_v(const std::uint8_t* bgr) {
    return static_cast<std::uint8_t>((112 * bgr[2] - 94 * bgr[1] - 18 * bgr[0] + 128) / 256 + 128);
}

}  // namespace

FaultInjectingSource::FaultInjectingSource(hal::FrameSource& inner, hal::Clock& clock,
                                           std::vector<CaptureFault> scenario)
    : inner_(inner), clock_(clock), scenario_(std::move(scenario)) {}

const CaptureFault* FaultInjectingSource::fault_at(std::int64_t index) const {
    for (const CaptureFault& f : scenario_)
        if (index >= f.at && index < f.at + f.frames) return &f;
    return nullptr;
}

hal::FrameFormat FaultInjectingSource::format_for(const CaptureFault* f) const {
    if (f == nullptr) return inner_format_;
    if (f->kind == Kind::kResize)
        return {f->width, f->height, f->width * 3, hal::PixelFormat::kBgr24};
    if (f->kind == Kind::kPixelFormat) {
        const int w = inner_format_.width;
        return {w, inner_format_.height, w * hal::bytes_per_pixel(f->pixel_format),
                f->pixel_format};
    }
    return inner_format_;
}

bool FaultInjectingSource::start() {
    if (!inner_.start()) return false;
    inner_format_ = inner_.format();
    std::size_t largest = inner_format_.size_bytes();
    for (const CaptureFault& f : scenario_) {
        if (drops_frames(f.kind)) continue;
        const hal::FrameFormat ff = format_for(&f);
        const bool convertible = f.kind != Kind::kPixelFormat ||
                                 f.pixel_format == hal::PixelFormat::kYuyv ||
                                 f.pixel_format == hal::PixelFormat::kGray8 ||
                                 f.pixel_format == hal::PixelFormat::kBgra32;
        if (inner_format_.pixel_format != hal::PixelFormat::kBgr24 || !ff.valid() || !convertible ||
            (ff.pixel_format == hal::PixelFormat::kYuyv && ff.width % 2 != 0)) {
            gone_error_ = "fault scenario: fault at frame " + std::to_string(f.at) +
                          " cannot be applied to the input's " +
                          std::string(hal::to_string(inner_format_.pixel_format)) + " frames";
            gone_ = true;
            return false;
        }
        largest = std::max(largest, ff.size_bytes());
    }
    pool_.assign(static_cast<std::size_t>(inner_.buffer_count()),
                 std::vector<std::uint8_t>(largest));
    borrowed_.assign(pool_.size(), false);
    format_ = format_for(fault_at(0));
    return true;
}

hal::SourceStatus FaultInjectingSource::next(hal::Frame& out, hal::Nanos timeout_ns) {
    const hal::Nanos call_start = clock_.now();
    for (;;) {
        const CaptureFault* f = fault_at(index_);
        if (f != nullptr && drops_frames(f->kind)) {
            hal::Frame in;
            const hal::SourceStatus st = inner_.next(in, timeout_ns);
            if (st == hal::SourceStatus::kFormatChange) inner_format_ = inner_.format();
            if (st != hal::SourceStatus::kFrame) return st;
            inner_.release(in);
            ++index_, ++dropped_;
            gone_ = gone_ || f->kind == Kind::kDisappear;
            if (clock_.now() - call_start >= timeout_ns) return hal::SourceStatus::kTimeout;
            continue;
        }
        const hal::FrameFormat want = format_for(f);
        if (!(want == format_)) {
            format_ = want;
            return hal::SourceStatus::kFormatChange;
        }
        int slot = -1;
        if (f != nullptr) {
            std::lock_guard lock(mutex_);
            for (std::size_t s = 0; s < borrowed_.size() && slot < 0; ++s)
                if (!borrowed_[s]) slot = static_cast<int>(s);
            if (slot < 0)
                return hal::SourceStatus::kTimeout;  // all lent: the caller gives one back
        }
        hal::Frame in;
        const hal::SourceStatus st = inner_.next(in, timeout_ns);
        if (st == hal::SourceStatus::kFormatChange) {
            inner_format_ = inner_.format();
            format_ = format_for(f);
        }
        if (st != hal::SourceStatus::kFrame) return st;
        ++index_;
        if (gone_) {
            // The device is back: a reopened V4L2 node counts from 0 again.
            gone_ = false;
            sequence_base_ = in.sequence;
        }
        if (f == nullptr) {
            out = in;
            out.sequence = in.sequence - sequence_base_;
            return hal::SourceStatus::kFrame;
        }
        {
            std::lock_guard lock(mutex_);
            borrowed_[static_cast<std::size_t>(slot)] = true;
        }
        out = in;
        out.format = format_;
        out.data = pool_[static_cast<std::size_t>(slot)].data();
        out.sequence = in.sequence - sequence_base_;
        out.buffer_index = kOwnIndex + slot;
        out.dmabuf_fd = -1;
        transform(*f, in, out);
        inner_.release(in);
        return hal::SourceStatus::kFrame;
    }
}

bool FaultInjectingSource::transform(const CaptureFault& f, const hal::Frame& in, hal::Frame& out) {
    const hal::FrameFormat& fi = in.format;
    const hal::FrameFormat& fo = out.format;
    switch (f.kind) {
        case Kind::kCorrupt:
            for (std::size_t i = 0; i < fo.size_bytes(); ++i) {
                noise_ = noise_ * 1664525u + 1013904223u;
                out.data[i] = static_cast<std::uint8_t>(noise_ >> 24);
            }
            return true;
        case Kind::kTruncate: {
            const std::size_t half =
                static_cast<std::size_t>(fi.stride) * static_cast<std::size_t>(fi.height / 2);
            std::memcpy(out.data, in.data, half);
            std::memset(out.data + half, 0, fo.size_bytes() - half);
            return true;
        }
        case Kind::kResize:
            for (int y = 0; y < fo.height; ++y) {
                const std::uint8_t* src =
                    in.data + static_cast<std::size_t>(y * fi.height / fo.height) * fi.stride;
                std::uint8_t* dst = out.data + static_cast<std::size_t>(y) * fo.stride;
                for (int x = 0; x < fo.width; ++x)
                    std::memcpy(dst + 3 * x, src + 3 * (x * fi.width / fo.width), 3);
            }
            return true;
        case Kind::kPixelFormat:
            for (int y = 0; y < fo.height; ++y) {
                const std::uint8_t* src = in.data + static_cast<std::size_t>(y) * fi.stride;
                std::uint8_t* dst = out.data + static_cast<std::size_t>(y) * fo.stride;
                for (int x = 0; x < fo.width; ++x) {
                    const std::uint8_t* p = src + 3 * x;
                    if (fo.pixel_format == hal::PixelFormat::kGray8) {
                        dst[x] = luma(p);
                    } else if (fo.pixel_format == hal::PixelFormat::kBgra32) {
                        std::memcpy(dst + 4 * x, p, 3);
                        dst[4 * x + 3] = 255;
                    } else if (x % 2 == 0) {  // YUYV: one chroma pair per two pixels
                        dst[2 * x] = luma(p), dst[2 * x + 1] = chroma_u(p);
                        dst[2 * x + 2] = luma(p + 3), dst[2 * x + 3] = chroma_v(p);
                    }
                }
            }
            return true;
        case Kind::kStall:
        case Kind::kDisappear:
            break;
    }
    return false;
}

void FaultInjectingSource::release(const hal::Frame& frame) {
    if (frame.buffer_index < kOwnIndex) {
        inner_.release(frame);
        return;
    }
    std::lock_guard lock(mutex_);
    borrowed_[static_cast<std::size_t>(frame.buffer_index - kOwnIndex)] = false;
}

}  // namespace endotower::sim
