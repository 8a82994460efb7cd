#include "endotower/media/media_image.hpp"

#include <dcmtk/config/osconfig.h>  // first, as DCMTK requires
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcrledrg.h>
#include <dcmtk/dcmdata/dcstack.h>
#include <dcmtk/dcmimage/diregist.h>  // colour images
#include <dcmtk/dcmimgle/dcmimage.h>
#include <dcmtk/dcmjpeg/djdecode.h>
#include <dcmtk/oflog/oflog.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace endotower::media {

namespace {

bool fail(std::string& error, const std::string& name, const std::string& what) {
    error = name + ": " + what;
    return false;
}

// Once per process: the compressed transfer syntaxes, and DCMTK's logging kept to
// fatal errors (the caller reports problems itself).
void init_dcmtk() {
    static std::once_flag once;
    std::call_once(once, [] {
        OFLog::configure(OFLogger::FATAL_LOG_LEVEL);
        DJDecoderRegistration::registerCodecs();
        DcmRLEDecoderRegistration::registerCodecs();
    });
}

bool is_dicom(const std::uint8_t* data, std::size_t size) {
    return size >= 132 && std::memcmp(data + 128, "DICM", 4) == 0;
}

// From the file, not from memory: DCMTK allocates an element's declared length when it
// reads it from memory, so a corrupt length field would ask for gigabytes. From a
// file, values over 64 KiB are only loaded when used, after the check below.
bool decode_dicom(const std::string& path, std::uintmax_t file_size, MediaImage& out,
                  std::string& error) {
    init_dcmtk();
    DcmFileFormat file;
    const OFCondition read =
        file.loadFile(OFFilename(path.c_str()), EXS_Unknown, EGL_noChange, 65536);
    if (read.bad())
        return fail(error, path, std::string("not a readable DICOM file (") + read.text() + ")");
    DcmStack stack;
    while (file.nextObject(stack, OFTrue).good()) {
        const Uint32 length = stack.top()->getLengthField();
        if (length != DCM_UndefinedLength && length > file_size)
            return fail(error, path,
                        "corrupt DICOM file (element " +
                            std::string(stack.top()->getTag().toString()) +
                            " longer than the file)");
    }
    DcmDataset* ds = file.getDataset();
    Uint16 rows = 0, cols = 0;
    if (ds->findAndGetUint16(DCM_Rows, rows).bad() ||
        ds->findAndGetUint16(DCM_Columns, cols).bad() || rows == 0 || cols == 0)
        return fail(error, path, "DICOM file without an image (no Rows/Columns)");
    if (rows > MediaImage::kMaxSide || cols > MediaImage::kMaxSide)
        return fail(error, path,
                    "DICOM image " + std::to_string(cols) + "x" + std::to_string(rows) +
                        " larger than " + std::to_string(MediaImage::kMaxSide));
    // The first frame only: a viewer shows one image per file.
    DicomImage image(&file, ds->getOriginalXfer(), CIF_UsePartialAccessToPixelData, 0, 1);
    if (image.getStatus() != EIS_Normal)
        return fail(error, path,
                    std::string("DICOM image not decodable (") +
                        DicomImage::getString(image.getStatus()) + ")");
    const bool mono = image.isMonochrome();
    if (mono) {
        // Window/level: the file's first VOI window, else its min/max range.
        if (image.getWindowCount() == 0 || !image.setWindow(0)) image.setMinMaxWindow();
    }
    const void* pixels = image.getOutputData(8, 0, 0);
    const auto w = static_cast<int>(image.getWidth()), h = static_cast<int>(image.getHeight());
    if (pixels == nullptr || w <= 0 || h <= 0)
        return fail(error, path, "DICOM pixel data could not be rendered");
    const auto* p = static_cast<const std::uint8_t*>(pixels);
    out.width = w, out.height = h;
    out.rgba.resize(static_cast<std::size_t>(w) * h * 4);
    const std::size_t n = static_cast<std::size_t>(w) * h;
    for (std::size_t i = 0; i < n; ++i) {
        std::uint8_t* q = &out.rgba[4 * i];
        if (mono)
            q[0] = q[1] = q[2] = p[i];
        else
            q[0] = p[3 * i], q[1] = p[3 * i + 1], q[2] = p[3 * i + 2];  // interleaved RGB
        q[3] = 255;
    }
    return true;
}

// The last chunk of a PNG is IEND; a JPEG ends with the EOI marker FF D9. libjpeg
// would fill a truncated JPEG with grey and call it a success.
bool complete_png_or_jpeg(const std::uint8_t* data, std::size_t size, std::string& what) {
    static constexpr std::uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    if (size >= 8 && std::memcmp(data, kPng, 8) == 0) {
        if (size >= 20 && std::memcmp(data + size - 8, "IEND", 4) == 0) return true;
        what = "truncated PNG (no IEND chunk at the end)";
        return false;
    }
    if (size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF) {
        // Some writers pad after EOI: look in the last 32 bytes.
        const std::size_t from = size > 32 ? size - 32 : 0;
        for (std::size_t i = size - 1; i > from; --i)
            if (data[i - 1] == 0xFF && data[i] == 0xD9) return true;
        what = "truncated JPEG (no end-of-image marker)";
        return false;
    }
    what = "neither DICOM, PNG nor JPEG";
    return false;
}

bool decode_png_jpeg(const std::uint8_t* data, std::size_t size, const std::string& name,
                     MediaImage& out, std::string& error) {
    std::string what;
    if (!complete_png_or_jpeg(data, size, what)) return fail(error, name, what);
    cv::Mat img;
    try {
        const cv::Mat buf(1, static_cast<int>(size), CV_8UC1, const_cast<std::uint8_t*>(data));
        img = cv::imdecode(buf, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception& e) {
        return fail(error, name, std::string("corrupt image (") + e.what() + ")");
    }
    if (img.empty()) return fail(error, name, "corrupt image (the decoder refused it)");
    if (img.cols > MediaImage::kMaxSide || img.rows > MediaImage::kMaxSide)
        return fail(error, name,
                    "image " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                        " larger than " + std::to_string(MediaImage::kMaxSide));
    if (img.depth() == CV_16U) img.convertTo(img, CV_8U, 1.0 / 257.0);
    if (img.depth() != CV_8U) return fail(error, name, "unsupported sample type");
    cv::Mat rgba;
    switch (img.channels()) {
        case 1:
            cv::cvtColor(img, rgba, cv::COLOR_GRAY2RGBA);
            break;
        case 3:
            cv::cvtColor(img, rgba, cv::COLOR_BGR2RGBA);
            break;
        case 4:
            cv::cvtColor(img, rgba, cv::COLOR_BGRA2RGBA);
            break;
        default:
            return fail(error, name, std::to_string(img.channels()) + " channels");
    }
    out.width = rgba.cols, out.height = rgba.rows;
    out.rgba.assign(rgba.datastart, rgba.dataend);
    return true;
}

}  // namespace

bool load_media_image(const std::string& path, MediaImage& out, std::string& error) {
    out = MediaImage{};
    const std::size_t slash = path.find_last_of('/');
    out.name = slash == std::string::npos ? path : path.substr(slash + 1);
    std::ifstream in(path, std::ios::binary);
    if (!in) return fail(error, path, std::string("cannot open (") + std::strerror(errno) + ")");
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                          std::istreambuf_iterator<char>());
    if (in.bad()) return fail(error, path, "read error");
    if (bytes.empty()) return fail(error, path, "empty file");
    const bool ok = is_dicom(bytes.data(), bytes.size())
                        ? decode_dicom(path, bytes.size(), out, error)
                        : decode_png_jpeg(bytes.data(), bytes.size(), path, out, error);
    if (!ok) out.rgba.clear(), out.width = out.height = 0;
    return ok;
}

}  // namespace endotower::media
