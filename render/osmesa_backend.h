// Internal: the OSMesa calls, kept in their own translation unit because <GL/osmesa.h>
// pulls in <GL/gl.h>, which must not meet glad's header. No gl* function is called there.
#pragma once

#include <string>

namespace ravel::render::osmesa {

// A GL core-profile context of at least 3.3 with an RGBA8 + depth24 default buffer.
void* create_context(std::string* error);
void destroy_context(void* context);
// Bind `buffer` (width * height * 4 bytes, RGBA8) as the default framebuffer.
bool make_current(void* context, void* buffer, int width, int height);
void* get_proc_address(const char* name);

}  // namespace ravel::render::osmesa
