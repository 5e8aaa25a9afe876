// PNG output through stb_image_write, written atomically (temp name, then rename).
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "render/renderer.h"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb/stb_image_write.h>

namespace ravel::render {

bool write_png(const std::string& path, int width, int height, const std::vector<std::uint8_t>& rgb,
               std::string* error) {
  if (width <= 0 || height <= 0 || rgb.size() != static_cast<std::size_t>(width) * height * 3) {
    if (error) *error = "write_png: image size does not match its pixels";
    return false;
  }
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  if (!stbi_write_png(tmp.c_str(), width, height, 3, rgb.data(), width * 3)) {
    if (error) *error = "cannot write " + tmp;
    std::remove(tmp.c_str());
    return false;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    if (error) *error = "cannot rename " + tmp + " to " + path + ": " + std::strerror(errno);
    std::remove(tmp.c_str());
    return false;
  }
  return true;
}

}  // namespace ravel::render
