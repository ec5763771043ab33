// The diffuse batch's vertex kernel for CPUs with AVX-512 (F, VL, DQ): this file is
// compiled with -mavx512f -mavx512vl -mavx512dq (core/CMakeLists.txt) and called only where the
// CPU has them (diffuse_batch.cpp).
#define GDVR_DIFFUSE_KERNEL shade_diffuse_vertices_avx512
#define GDVR_ENVIRONMENT_KERNEL add_environment_avx512
#include "core/render/diffuse_vertex_kernel.inl"
