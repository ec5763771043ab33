// The vector batch's vertex kernel for CPUs with AVX2: this file is
// compiled with -mavx2 (core/CMakeLists.txt) and called only where the
// CPU has it (vector_batch.cpp).
#define GDVR_VERTEX_KERNEL shade_vector_vertices_avx2
#define GDVR_ENVIRONMENT_KERNEL add_environment_avx2
#include "core/render/vector_vertex_kernel.inl"
