// Linked into every executable of a ThreadSanitizer build (the tsan preset; see the
// top-level CMakeLists.txt), nowhere else.
//
// OpenCV runs parallel_for_ on Debian's TBB, which is not instrumented: TSan does not
// see its hand-offs and reports every parallel loop's body (and the buffers it frees)
// as racing with the caller. Those reports say nothing about our code, and would hide
// the ones that do, so under TSan OpenCV runs its loops on the calling thread. Our own
// threads (the pipeline's video and analysis threads, capture and input sources, the
// undistorter's helper) are what TSan checks.
//
// Mesa's software renderer (llvmpipe, behind the overlay renderer's and the display
// tests' EGL) rasterises on threads of its own, in the same uninstrumented way:
// LP_NUM_THREADS=0 (Mesa's variable, read when the driver loads, after this runs) keeps
// it on the calling thread too, unless the environment already says otherwise.
//
// FFmpeg (behind OpenCV's VideoCapture and VideoWriter: recordings in, video files out)
// decodes on threads of its own too, and OpenCV 4.6 has no way to ask for one: reports
// with FFmpeg's libraries in a stack are silenced (its buffers are handed to us only
// as copies, cv::Mat frames that OpenCV owns).
//
// GDAL (initialised by OpenCV's image codecs on first use) takes its own mutexes in an
// order TSan calls a potential deadlock, inside the uninstrumented library on one
// thread: that library's lock-order reports are silenced, nothing else.
#include <cstdlib>
#include <opencv2/core/utility.hpp>

namespace {

const bool kOpenCvOnTheCallingThread = (cv::setNumThreads(1), true);
const bool kLlvmpipeOnTheCallingThread = (setenv("LP_NUM_THREADS", "0", 0), true);

}  // namespace

// The name is TSan's hook, looked up by the runtime.
extern "C" const char* __tsan_default_suppressions() {
    return "deadlock:libgdal.so\n"
           "race:libavcodec.so\n"
           "race:libavutil.so\n"
           "race:libavformat.so\n";
}
