#include "render/gl.h"
#include "render/renderer.h"

namespace ravel::render {

bool load_gl(GlProcLoader loader, std::string* error) {
  if (!loader) {
    if (error) *error = "no GL proc-address function";
    return false;
  }
  const int version = gladLoadGL(reinterpret_cast<GLADloadfunc>(loader));
  if (version == 0) {
    if (error) *error = "could not load GL entry points (no current context?)";
    return false;
  }
  if (GLAD_VERSION_MAJOR(version) < 3 || (GLAD_VERSION_MAJOR(version) == 3 && GLAD_VERSION_MINOR(version) < 3)) {
    if (error)
      *error = "OpenGL 3.3 needed, context gives " + std::to_string(GLAD_VERSION_MAJOR(version)) + "." +
               std::to_string(GLAD_VERSION_MINOR(version));
    return false;
  }
  return true;
}

}  // namespace ravel::render
