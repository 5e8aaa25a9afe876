#include "render/osmesa_backend.h"

#include <GL/osmesa.h>

namespace ravel::render::osmesa {

void* create_context(std::string* error) {
  // Ask for a core profile; llvmpipe hands out 4.5 core. A compatibility context would
  // also run our shaders, but core is what the window path gets, so test that.
  const int attribs[] = {OSMESA_FORMAT,
                         OSMESA_RGBA,
                         OSMESA_DEPTH_BITS,
                         24,
                         OSMESA_STENCIL_BITS,
                         0,
                         OSMESA_ACCUM_BITS,
                         0,
                         OSMESA_PROFILE,
                         OSMESA_CORE_PROFILE,
                         OSMESA_CONTEXT_MAJOR_VERSION,
                         3,
                         OSMESA_CONTEXT_MINOR_VERSION,
                         3,
                         0};
  OSMesaContext ctx = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!ctx && error) *error = "OSMesaCreateContextAttribs failed to give a 3.3 core context";
  return ctx;
}

void destroy_context(void* context) {
  if (context) OSMesaDestroyContext(static_cast<OSMesaContext>(context));
}

bool make_current(void* context, void* buffer, int width, int height) {
  return OSMesaMakeCurrent(static_cast<OSMesaContext>(context), buffer, GL_UNSIGNED_BYTE, width, height) == GL_TRUE;
}

void* get_proc_address(const char* name) {
  return reinterpret_cast<void*>(OSMesaGetProcAddress(name));
}

}  // namespace ravel::render::osmesa
