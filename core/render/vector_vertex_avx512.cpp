// The vector batch's vertex kernel for CPUs with AVX-512 (F, VL, DQ): this file is
// compiled with -mavx512f -mavx512vl -mavx512dq (core/CMakeLists.txt) and called only where the
// CPU has them (vector_batch.cpp).
#define GDVR_VERTEX_KERNEL shade_vector_vertices_avx512
#define GDVR_ENVIRONMENT_KERNEL add_environment_avx512
#include "core/render/vector_vertex_kernel.inl"
