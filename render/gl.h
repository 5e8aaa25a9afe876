// Internal: the generated glad GL 3.3 core loader. Only ravel_render's own sources include
// this; the public header (renderer.h) stays free of GL headers.
#pragma once

#include <glad/gl.h>
