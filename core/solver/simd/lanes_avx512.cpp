// The lane kernels for AVX-512 (see lanes_kernels.inc; built with -mavx512f -mavx512vl
// -mavx512dq: the same four-wide code with 32 vector registers and mask registers).
#define RAVEL_LANES_ISA avx512
#include "lanes_kernels.inc"
