// MjpegDecoder: one V4L2 MJPEG buffer (a baseline JPEG) decoded with libjpeg-turbo
// straight into the caller's BGR24 frame, allocation-free in steady state.
//
// libjpeg's image pool (everything jpeg_start_decompress allocates) is served from an
// arena owned here: the first frames size it (blocks beyond it are allocated and, at
// the end of that frame, merged into one arena of the size seen), then every frame of
// the same geometry reuses it. The permanent pool (tables, source manager) is
// libjpeg's own and is filled once. Frames without DHT segments (many UVC cameras omit
// them) decode with the standard tables of JPEG Annex K.3 (libjpeg's encoder defaults),
// restored before every frame so that an earlier frame's DHT does not linger.
//
// decode() never throws nor aborts: libjpeg's errors and warnings (a truncated buffer
// ends in "Premature end of JPEG file") end the frame through setjmp/longjmp and it is
// rejected. Rejected too: an empty buffer, progressive or multi-scan JPEG (cameras send
// baseline; several scans would need whole-image coefficient buffers), and a size other
// than the negotiated one. Only libjpeg's "extraneous bytes before marker" warning is
// tolerated: the image has been decoded in full by then. Not thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

namespace endotower::v4l2 {

enum class MjpegResult : std::uint8_t {
    kDecoded,
    kCorrupt,      // empty, truncated or damaged data (libjpeg error or warning)
    kUnsupported,  // progressive / multi-scan
    kWrongSize,    // decodes, but not at the size the frame was set up for
};

class MjpegDecoder {
public:
    // `device` is named in messages. Creates the libjpeg object (allocates).
    explicit MjpegDecoder(std::string_view device);
    ~MjpegDecoder();
    MjpegDecoder(const MjpegDecoder&) = delete;
    MjpegDecoder& operator=(const MjpegDecoder&) = delete;

    // Decodes `size` bytes at `jpeg` (borrowed for the call) into `out`: width x height
    // BGR24 pixels, rows `stride` bytes apart (>= 3 * width). `sequence` is the capture
    // buffer's, for the message. On failure `out` may hold part of a picture.
    MjpegResult decode(const std::uint8_t* jpeg, std::size_t size, std::uint64_t sequence,
                       std::uint8_t* out, int width, int height, int stride);

    // Why the last decode failed: "DEVICE: MJPEG buffer sequence N: REASON" (empty after
    // a success). Assigned without allocating once the first message has been written.
    const std::string& message() const;
    std::uint64_t decoded() const;        // frames decoded
    std::uint64_t rejected() const;       // frames that failed, whatever the reason
    std::size_t arena_bytes() const;      // the image-pool arena's size now
    std::uint64_t arena_growths() const;  // times the arena was resized (first frames)

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace endotower::v4l2
