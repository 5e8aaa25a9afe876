#include "version.h"

namespace ravel {

const char* version() { return RAVEL_VERSION; }

}  // namespace ravel
