#include "endotower/v4l2/mjpeg_decoder.hpp"

// clang-format off
#include <cstdio>  // jpeglib.h needs FILE and size_t first
#include <jpeglib.h>
#include <jerror.h>
// clang-format on

#include <algorithm>
#include <csetjmp>
#include <cstdlib>
#include <cstring>

namespace endotower::v4l2 {

namespace {

// libjpeg-turbo aligns its pool objects to ALIGN_SIZE (32 with SIMD) and pads sample
// rows to 2 * ALIGN_SIZE so that SIMD upsampling may run past the width; 64 covers both.
constexpr std::size_t kAlign = 64;
constexpr std::size_t kMaxObject = 1'000'000'000;  // libjpeg's MAX_ALLOC_CHUNK

std::size_t round_up(std::size_t n, std::size_t a) {
    return (n + a - 1) / a * a;
}

// A block allocated while the arena was too small (first frames); data at +kAlign.
struct Overflow {
    Overflow* next;
};

// The image pool: bump allocation, reset by free_pool(JPOOL_IMAGE).
struct Arena {
    unsigned char* base = nullptr;
    std::size_t capacity = 0;
    std::size_t used = 0;
    std::size_t demand = 0;  // bytes this image asked for, inside the arena or not
    Overflow* overflow = nullptr;
    std::uint64_t growths = 0;
};

// What libjpeg's callbacks reach through cinfo->client_data. Trivially destructible:
// longjmp leaves frames that point at it.
struct Context {
    jpeg_error_mgr err;
    std::jmp_buf jump;
    MjpegResult on_jump = MjpegResult::kCorrupt;
    char reason[JMSG_LENGTH_MAX + 96];
    Arena arena;
    jpeg_memory_mgr original;  // libjpeg's methods, for the permanent pool
    // JPEG Annex K.3 tables (from libjpeg's encoder defaults), restored before each frame.
    JHUFF_TBL standard_dc[2];
    JHUFF_TBL standard_ac[2];
    bool have_standard = false;
};

Context& context(j_common_ptr cinfo) {
    return *static_cast<Context*>(cinfo->client_data);
}

void free_overflow(Arena& a) {
    while (a.overflow) {
        Overflow* next = a.overflow->next;
        std::free(a.overflow);
        a.overflow = next;
    }
}

void* arena_take(j_common_ptr cinfo, std::size_t n) {
    if (n > kMaxObject) ERREXIT1(cinfo, JERR_OUT_OF_MEMORY, 7);
    Arena& a = context(cinfo).arena;
    n = round_up(n, kAlign);
    a.demand += n;
    if (a.used + n <= a.capacity) {
        void* p = a.base + a.used;
        a.used += n;
        return p;
    }
    void* mem = nullptr;
    if (posix_memalign(&mem, kAlign, kAlign + n) != 0) ERREXIT1(cinfo, JERR_OUT_OF_MEMORY, 4);
    auto* block = static_cast<Overflow*>(mem);
    block->next = a.overflow;
    a.overflow = block;
    return static_cast<unsigned char*>(mem) + kAlign;
}

void* alloc_small(j_common_ptr cinfo, int pool, std::size_t n) {
    if (pool != JPOOL_IMAGE) return context(cinfo).original.alloc_small(cinfo, pool, n);
    return arena_take(cinfo, n);
}

void* alloc_large(j_common_ptr cinfo, int pool, std::size_t n) {
    if (pool != JPOOL_IMAGE) return context(cinfo).original.alloc_large(cinfo, pool, n);
    return arena_take(cinfo, n);
}

JSAMPARRAY alloc_sarray(j_common_ptr cinfo, int pool, JDIMENSION samples, JDIMENSION rows) {
    if (pool != JPOOL_IMAGE)
        return context(cinfo).original.alloc_sarray(cinfo, pool, samples, rows);
    const std::size_t row =
        round_up(static_cast<std::size_t>(samples) * sizeof(JSAMPLE), 2 * kAlign);
    if (rows > 0 && row > kMaxObject / rows) ERREXIT(cinfo, JERR_WIDTH_OVERFLOW);
    auto* result = static_cast<JSAMPARRAY>(arena_take(cinfo, rows * sizeof(JSAMPROW)));
    auto* data = static_cast<JSAMPLE*>(arena_take(cinfo, row * rows));
    for (JDIMENSION i = 0; i < rows; ++i) result[i] = data + i * row;
    return result;
}

JBLOCKARRAY alloc_barray(j_common_ptr cinfo, int pool, JDIMENSION blocks, JDIMENSION rows) {
    if (pool != JPOOL_IMAGE) return context(cinfo).original.alloc_barray(cinfo, pool, blocks, rows);
    const std::size_t row = static_cast<std::size_t>(blocks) * sizeof(JBLOCK);
    if (rows > 0 && row > kMaxObject / rows) ERREXIT(cinfo, JERR_WIDTH_OVERFLOW);
    auto* result = static_cast<JBLOCKARRAY>(arena_take(cinfo, rows * sizeof(JBLOCKROW)));
    auto* data = static_cast<JBLOCKROW>(arena_take(cinfo, row * rows));
    for (JDIMENSION i = 0; i < rows; ++i) result[i] = data + i * blocks;
    return result;
}

// Only multi-scan images ask for whole-image (virtual) arrays; decode() refuses those
// before jpeg_start_decompress, so reaching here means a check missed one.
[[noreturn]] void refuse_whole_image(j_common_ptr cinfo) {
    Context& c = context(cinfo);
    std::snprintf(c.reason, sizeof c.reason,
                  "multi-scan JPEG is not supported (needs whole-image buffers)");
    c.on_jump = MjpegResult::kUnsupported;
    std::longjmp(c.jump, 1);
}
jvirt_sarray_ptr request_virt_sarray(j_common_ptr cinfo, int, boolean, JDIMENSION, JDIMENSION,
                                     JDIMENSION) {
    refuse_whole_image(cinfo);
}
jvirt_barray_ptr request_virt_barray(j_common_ptr cinfo, int, boolean, JDIMENSION, JDIMENSION,
                                     JDIMENSION) {
    refuse_whole_image(cinfo);
}

// End of an image (jpeg_finish_decompress, jpeg_abort): the arena is empty again. If the
// image needed more than the arena, it becomes one block of that size for the next one.
void free_pool(j_common_ptr cinfo, int pool) {
    Context& c = context(cinfo);
    if (pool == JPOOL_IMAGE) {
        Arena& a = c.arena;
        free_overflow(a);
        if (a.demand > a.capacity) {
            std::free(a.base);
            void* mem = nullptr;
            const bool ok = posix_memalign(&mem, kAlign, a.demand) == 0;
            a.base = ok ? static_cast<unsigned char*>(mem) : nullptr;
            a.capacity = ok ? a.demand : 0;  // out of memory: the next image overflows again
            ++a.growths;
        }
        a.used = 0;
        a.demand = 0;
    }
    c.original.free_pool(cinfo, pool);  // closes libjpeg's own image-pool bookkeeping
}

[[noreturn]] void error_exit(j_common_ptr cinfo) {
    Context& c = context(cinfo);
    char text[JMSG_LENGTH_MAX];
    c.err.format_message(cinfo, text);
    std::snprintf(c.reason, sizeof c.reason, "corrupt JPEG (%s)", text);
    c.on_jump = MjpegResult::kCorrupt;
    std::longjmp(c.jump, 1);
}

// A warning means damaged data (a truncated buffer is padded with a fake EOI and decodes
// grey), so the frame ends, except for junk before a marker after the last MCU.
void emit_message(j_common_ptr cinfo, int level) {
    if (level >= 0) return;  // trace messages
    if (cinfo->err->msg_code == JWRN_EXTRANEOUS_DATA) {
        ++cinfo->err->num_warnings;
        return;
    }
    error_exit(cinfo);
}

void output_message(j_common_ptr) {}

// A DHT-less frame must decode with the standard tables, not with those a DHT of an
// earlier frame left in the slots (libjpeg-turbo 2.1 only fills empty slots). A frame's
// own DHT overwrites these copies.
void restore_standard_tables(const Context* c, jpeg_decompress_struct* cinfo) {
    if (!c->have_standard) return;
    for (int i = 0; i < 2; ++i) {
        if (cinfo->dc_huff_tbl_ptrs[i]) *cinfo->dc_huff_tbl_ptrs[i] = c->standard_dc[i];
        if (cinfo->ac_huff_tbl_ptrs[i]) *cinfo->ac_huff_tbl_ptrs[i] = c->standard_ac[i];
    }
}

// C-style on purpose: libjpeg's errors longjmp back to the setjmp here, so no object
// with a destructor may live in this frame or in the libjpeg frames it calls.
MjpegResult decode_jpeg(Context* c, jpeg_decompress_struct* cinfo, const std::uint8_t* jpeg,
                        std::size_t size, std::uint8_t* out, int width, int height, int stride) {
    if (setjmp(c->jump) != 0) {
        jpeg_abort_decompress(cinfo);  // frees the image pool: the arena is reset
        return c->on_jump;
    }
    restore_standard_tables(c, cinfo);
    jpeg_mem_src(cinfo, jpeg, static_cast<unsigned long>(size));
    jpeg_read_header(cinfo, TRUE);
    if (cinfo->progressive_mode || jpeg_has_multiple_scans(cinfo)) {
        std::snprintf(c->reason, sizeof c->reason,
                      "%s JPEG is not supported (cameras send baseline)",
                      cinfo->progressive_mode ? "progressive" : "multi-scan");
        jpeg_abort_decompress(cinfo);
        return MjpegResult::kUnsupported;
    }
    if (cinfo->image_width != static_cast<JDIMENSION>(width) ||
        cinfo->image_height != static_cast<JDIMENSION>(height)) {
        std::snprintf(c->reason, sizeof c->reason, "the JPEG is %ux%u, the format is %dx%d",
                      cinfo->image_width, cinfo->image_height, width, height);
        jpeg_abort_decompress(cinfo);
        return MjpegResult::kWrongSize;
    }
    cinfo->out_color_space = JCS_EXT_BGR;
    jpeg_start_decompress(cinfo);
    JSAMPROW rows[16];
    while (cinfo->output_scanline < cinfo->output_height) {
        const JDIMENSION first = cinfo->output_scanline;
        const JDIMENSION n = std::min<JDIMENSION>(16, cinfo->output_height - first);
        for (JDIMENSION i = 0; i < n; ++i)
            rows[i] = out + static_cast<std::size_t>(first + i) * static_cast<std::size_t>(stride);
        jpeg_read_scanlines(cinfo, rows, n);
    }
    jpeg_finish_decompress(cinfo);
    return MjpegResult::kDecoded;
}

bool create_jpeg(Context* c, jpeg_decompress_struct* cinfo) {
    if (setjmp(c->jump) != 0) return false;
    jpeg_create_decompress(cinfo);
    return true;
}

// The standard Huffman tables as libjpeg's encoder sets them by default.
void capture_standard_tables(Context* c) {
    jpeg_compress_struct enc;
    std::memset(&enc, 0, sizeof enc);
    enc.err = &c->err;
    enc.client_data = c;
    if (setjmp(c->jump) != 0) {
        jpeg_destroy_compress(&enc);
        return;
    }
    jpeg_create_compress(&enc);
    enc.in_color_space = JCS_RGB;
    enc.input_components = 3;
    jpeg_set_defaults(&enc);
    for (int i = 0; i < 2; ++i) {
        c->standard_dc[i] = *enc.dc_huff_tbl_ptrs[i];
        c->standard_ac[i] = *enc.ac_huff_tbl_ptrs[i];
    }
    c->have_standard = true;
    jpeg_destroy_compress(&enc);
}

}  // namespace

struct MjpegDecoder::Impl {
    std::string device;
    std::string message;
    Context ctx{};
    jpeg_decompress_struct cinfo{};
    bool ready = false;
    std::uint64_t decoded = 0;
    std::uint64_t rejected = 0;
};

MjpegDecoder::MjpegDecoder(std::string_view device) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.device = device;
    m.message.reserve(sizeof m.ctx.reason + 160);  // the longest message: no allocation later
    jpeg_std_error(&m.ctx.err);
    m.ctx.err.error_exit = error_exit;
    m.ctx.err.emit_message = emit_message;
    m.ctx.err.output_message = output_message;
    m.cinfo.err = &m.ctx.err;
    m.cinfo.client_data = &m.ctx;
    capture_standard_tables(&m.ctx);
    if (!create_jpeg(&m.ctx, &m.cinfo)) return;
    jpeg_memory_mgr& mem = *m.cinfo.mem;
    m.ctx.original = mem;
    mem.alloc_small = alloc_small;
    mem.alloc_large = alloc_large;
    mem.alloc_sarray = alloc_sarray;
    mem.alloc_barray = alloc_barray;
    mem.request_virt_sarray = request_virt_sarray;
    mem.request_virt_barray = request_virt_barray;
    mem.free_pool = free_pool;
    m.ready = true;
}

MjpegDecoder::~MjpegDecoder() {
    Impl& m = *impl_;
    if (m.ready) jpeg_destroy_decompress(&m.cinfo);
    free_overflow(m.ctx.arena);
    std::free(m.ctx.arena.base);
}

MjpegResult MjpegDecoder::decode(const std::uint8_t* jpeg, std::size_t size, std::uint64_t sequence,
                                 std::uint8_t* out, int width, int height, int stride) {
    Impl& m = *impl_;
    MjpegResult r = MjpegResult::kCorrupt;
    if (!m.ready)
        std::snprintf(m.ctx.reason, sizeof m.ctx.reason, "libjpeg could not be set up");
    else if (jpeg == nullptr || size == 0)
        std::snprintf(m.ctx.reason, sizeof m.ctx.reason, "empty buffer (0 bytes)");
    else if (out == nullptr || width <= 0 || height <= 0 || stride < 3 * width)
        std::snprintf(m.ctx.reason, sizeof m.ctx.reason, "no output frame (%dx%d, stride %d)",
                      width, height, stride);
    else
        r = decode_jpeg(&m.ctx, &m.cinfo, jpeg, size, out, width, height, stride);
    if (r == MjpegResult::kDecoded) {
        ++m.decoded;
        m.message.clear();
        return r;
    }
    ++m.rejected;
    char text[sizeof m.ctx.reason + 160];
    std::snprintf(text, sizeof text, "%.100s: MJPEG buffer sequence %llu: %s; frame dropped",
                  m.device.c_str(), static_cast<unsigned long long>(sequence), m.ctx.reason);
    m.message.assign(text);
    return r;
}

const std::string& MjpegDecoder::message() const {
    return impl_->message;
}
std::uint64_t MjpegDecoder::decoded() const {
    return impl_->decoded;
}
std::uint64_t MjpegDecoder::rejected() const {
    return impl_->rejected;
}
std::size_t MjpegDecoder::arena_bytes() const {
    return impl_->ctx.arena.capacity;
}
std::uint64_t MjpegDecoder::arena_growths() const {
    return impl_->ctx.arena.growths;
}

}  // namespace endotower::v4l2
