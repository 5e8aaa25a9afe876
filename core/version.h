// What this binary is: ravel's version and the source commit it was built from (recorded
// in summary.json and in a sweep's case records, printed by `ravel --version`).
#pragma once

namespace ravel {

const char* version();        // the project version of CMakeLists.txt, e.g. "0.1.0"
const char* source_commit();  // git describe of the source tree at build time ("-dirty" when edited)

}  // namespace ravel
