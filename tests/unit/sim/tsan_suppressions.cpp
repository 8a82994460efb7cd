// ThreadSanitizer: OpenCV's image codecs initialise GDAL on first use, and GDAL's
// own mutexes (CPLAcquireMutex) trip a lock-order report inside the uninstrumented
// library on a single thread. Not ours; silence just that library. Unused without
// -fsanitize=thread.
// The name is TSan's hook, looked up by the runtime.
// NOLINTNEXTLINE(bugprone-reserved-identifier)
extern "C" const char* __tsan_default_suppressions() {
    return "deadlock:libgdal.so\n";
}
