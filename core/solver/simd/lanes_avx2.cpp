// The lane kernels for AVX2 (see lanes_kernels.inc; built with -mavx2).
#define RAVEL_LANES_ISA avx2
#include "lanes_kernels.inc"
