// Small GLES2/EGL helpers: shader programs with fixed attribute slots, and error
// codes as text ("GL_INVALID_OPERATION (0x0502)").
// Requires a current GLES2 context.
#pragma once

#include <string>

namespace endotower::gles {

// Compiles and links; attribute i of `attributes` (nullptr-terminated) is bound to
// slot i. 0 on error, with `error` naming the stage and the compiler's log.
unsigned link_program(const char* vertex_source, const char* fragment_source,
                      const char* const* attributes, std::string& error);

std::string gl_error_text(unsigned code);
std::string egl_error_text(int code);

}  // namespace endotower::gles
