#include "gl_program.hpp"

#include <EGL/egl.h>
#include <GLES2/gl2.h>

#include <cstdio>

namespace endotower::gles {

namespace {

unsigned compile(unsigned type, const char* source, std::string& error) {
    const unsigned s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = {};
        glGetShaderInfoLog(s, sizeof log, nullptr, log);
        error = std::string(type == GL_VERTEX_SHADER ? "vertex" : "fragment") +
                " shader does not compile: " + log;
        glDeleteShader(s);
        return 0;
    }
    return s;
}

std::string hex_code(const char* name, unsigned code) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s (0x%04x)", name, code);
    return buf;
}

}  // namespace

unsigned link_program(const char* vertex_source, const char* fragment_source,
                      const char* const* attributes, std::string& error) {
    const unsigned vs = compile(GL_VERTEX_SHADER, vertex_source, error);
    if (vs == 0) return 0;
    const unsigned fs = compile(GL_FRAGMENT_SHADER, fragment_source, error);
    if (fs == 0) {
        glDeleteShader(vs);
        return 0;
    }
    const unsigned p = glCreateProgram();
    glAttachShader(p, vs);
    glAttachShader(p, fs);
    for (unsigned i = 0; attributes[i] != nullptr; ++i) glBindAttribLocation(p, i, attributes[i]);
    glLinkProgram(p);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = {};
        glGetProgramInfoLog(p, sizeof log, nullptr, log);
        error = std::string("glLinkProgram: ") + log;
        glDeleteProgram(p);
        return 0;
    }
    return p;
}

std::string gl_error_text(unsigned code) {
    switch (code) {
        case GL_INVALID_ENUM: return hex_code("GL_INVALID_ENUM", code);
        case GL_INVALID_VALUE: return hex_code("GL_INVALID_VALUE", code);
        case GL_INVALID_OPERATION: return hex_code("GL_INVALID_OPERATION", code);
        case GL_OUT_OF_MEMORY: return hex_code("GL_OUT_OF_MEMORY", code);
        case GL_INVALID_FRAMEBUFFER_OPERATION:
            return hex_code("GL_INVALID_FRAMEBUFFER_OPERATION", code);
        case GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT:
            return hex_code("GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT", code);
        case GL_FRAMEBUFFER_UNSUPPORTED: return hex_code("GL_FRAMEBUFFER_UNSUPPORTED", code);
        default: return hex_code("GL error", code);
    }
}

std::string egl_error_text(int code) {
    switch (code) {
        case EGL_NOT_INITIALIZED: return hex_code("EGL_NOT_INITIALIZED", code);
        case EGL_BAD_ACCESS: return hex_code("EGL_BAD_ACCESS", code);
        case EGL_BAD_ALLOC: return hex_code("EGL_BAD_ALLOC", code);
        case EGL_BAD_ATTRIBUTE: return hex_code("EGL_BAD_ATTRIBUTE", code);
        case EGL_BAD_CONFIG: return hex_code("EGL_BAD_CONFIG", code);
        case EGL_BAD_CONTEXT: return hex_code("EGL_BAD_CONTEXT", code);
        case EGL_BAD_DISPLAY: return hex_code("EGL_BAD_DISPLAY", code);
        case EGL_BAD_MATCH: return hex_code("EGL_BAD_MATCH", code);
        case EGL_BAD_PARAMETER: return hex_code("EGL_BAD_PARAMETER", code);
        case EGL_BAD_SURFACE: return hex_code("EGL_BAD_SURFACE", code);
        default: return hex_code("EGL error", static_cast<unsigned>(code));
    }
}

}  // namespace endotower::gles
