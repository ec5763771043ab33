// The path batch (path_batch.h) for a scene that FrameScene laid out as
// records (vector_scene.h): the paths' state as struct of arrays, each
// vertex on a diffuse, rough Beckmann conductor or smooth plastic triangle
// shaded eight paths at a time by an AVX2 or AVX-512 kernel
// (vector_vertex_kernel.inl), the rays cast as the scalar batch casts them.
// Every path's radiance is the scalar batch's bit for bit, so an image does
// not depend on which CPU rendered it. Lanes take the scalar
// stages for what the kernel leaves out: emission seen along a ray (a few
// per cent of hits, scalar either way) and whole vertices on shapes it does
// not shade (spheres, other BSDFs: kShapeScalar); a hit on a shape that
// reflects nothing ends the path there, and the last ray under max_depth is
// cast from the batch's own state, as cast_last_stream casts it. The kernel
// samples triangle and sphere area lights and environment maps, and adds an
// environment map's radiance along rays that leave; next-event estimation
// towards other emitters calls FrameScene's own sampling lane by lane.
//
// Why: one path at a time, gdvr's own code between two Embree calls is bound
// by its instruction count, and eight lanes share those instructions. On cbox
// this made the path tracer's own code per ray about 1.9x faster; shading
// conductors and sampling sphere lights here made veach-mis renders 1.33x
// faster, the environment map and smooth plastic matpreview's 1.13x and then
// 1.115x (docs/renderer.md, "The vector batch").
#pragma once

#include <string>
#include <vector>

#include "core/render/path_stages.h"

namespace gdvr {

// A vertex kernel (vector_batch_state.h) and the instruction set it needs.
struct VectorKernel {
  const char* isa;  // "avx512", "avx2"
  void (*shade)(const VectorSceneView& scene, VectorBatchState* state);
  void (*add_environment)(const VectorSceneView& scene, VectorBatchState* state, const int32_t* lanes, int n,
                          bool hide_camera_rays);
};
// The kernels this CPU can run, fastest first; empty where it has no AVX2
// (or the build is not for x86-64).
const std::vector<VectorKernel>& vector_kernels();

// Whether trace_vector_batch can run: `scene` has vector records and this
// CPU has a kernel.
bool vector_batch_available(const FrameScene& scene);

// Why trace_tile_samples will not use the vector batch for `scene` with
// these settings and `paths_in_flight` (empty: it will), for the frame
// statistics' list of what the pipeline left out.
std::string why_no_vector_batch(const FrameScene& scene, const PathTracerSettings& settings, int paths_in_flight);

// trace_path_batch's work for paths[0..n) (n <= kPathBatch, all at depth 0):
// out[i] is path i's sample, as the scalar batch gives it. `kernel`: one of
// vector_kernels() (tests run each); null, the fastest. Where the batch is
// not available (vector_batch_available), the scalar batch runs instead.
void trace_vector_batch(const FrameScene& scene, const PathTracerSettings& settings, PathState* paths, int n,
                        RayStream& stream, PathCounters& counters, PathSample* out,
                        const VectorKernel* kernel = nullptr);

// start_path() for lane i of a batch that trace_started_vector_batch will
// trace: trace_tile_samples starts its paths in place (copying them in from
// PathStates took 2.4 % of veach-mis's render time).
void start_lane(VectorBatchState* s, int i, const Ray& camera_ray, const Sampler& sampler);

// trace_vector_batch for lanes [0, n) of *s, started by start_lane. Needs
// vector_batch_available(scene) (or a kernel given).
void trace_started_vector_batch(const FrameScene& scene, const PathTracerSettings& settings, VectorBatchState* s,
                                int n, RayStream& stream, PathCounters& counters, PathSample* out,
                                const VectorKernel* kernel = nullptr);

}  // namespace gdvr
