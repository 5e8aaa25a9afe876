// Shared by the reference (limit.cpp) and the fast search (limit_fast.cpp).
#pragma once

#include "limit.h"

namespace ravel::studies {

// A warning for each run on the wrong side of [lo_mps, hi_mps] (outcome not a threshold).
void warn_non_monotone(LimitResult& res);
// error_mps and error_note from the bracket, the warnings and the cancelled runs.
void describe_error(LimitResult& res);

}  // namespace ravel::studies
