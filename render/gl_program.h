// Shader programs from the shaders embedded at build time (render/renderer.cpp). Needs a
// current context with GL loaded. Throws std::runtime_error with the compiler's log.
#pragma once

#include "render/gl.h"

namespace ravel::render {

GLuint link_program(const char* vert, const char* frag);

}  // namespace ravel::render
