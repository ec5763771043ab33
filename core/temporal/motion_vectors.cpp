#include "core/temporal/motion_vectors.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <cmath>
#include <cstdlib>

#include "core/render/perspective_camera.h"

namespace gdvr {

MotionField compute_motion_field(const FrameScene& scene, const Scene& desc_t, const Scene& desc_other, int width,
                                 int height, int threads) {
  MotionField field;
  field.offsets = Image(width, height, 3);
  const PerspectiveCamera cam_t(desc_t.camera, width, height);
  const PerspectiveCamera cam_other(desc_other.camera, width, height);
  const bool camera_moves = !(desc_t.camera.to_world == desc_other.camera.to_world);
  // Per shape: the rigid map from frame t to the other frame (identity when static).
  std::vector<Transform> carry(desc_t.shapes.size());
  std::vector<bool> moves(desc_t.shapes.size(), false);
  for (size_t i = 0; i < desc_t.shapes.size() && i < desc_other.shapes.size(); ++i) {
    moves[i] = desc_t.shapes[i].to_world != desc_other.shapes[i].to_world;
    if (moves[i]) carry[i] = desc_other.shapes[i].to_world * desc_t.shapes[i].to_world.inverse();
  }
  Image& out = field.offsets;
  auto rows = [&](const tbb::blocked_range<int>& r) {
    for (int y = r.begin(); y < r.end(); ++y)
      for (int x = 0; x < width; ++x) {
        const Vec2f centre(float(x) + 0.5f, float(y) + 0.5f);
        Ray ray = cam_t.generate_ray(centre);
        SurfaceInteraction si;
        Vec2f film;
        bool ok;
        if (scene.intersect_camera_ray(ray, &si)) {
          Vec3f p = si.p;
          if (si.shape >= 0 && size_t(si.shape) < moves.size() && moves[size_t(si.shape)])
            p = carry[size_t(si.shape)].point(p);
          if (!camera_moves && p.x == si.p.x && p.y == si.p.y && p.z == si.p.z) {
            // Nothing moved under this pixel: exactly zero, not the round-off
            // (~1e-5 px) of projecting the hit back, which the replay map
            // would take for a sub-pixel motion and rotate the jitter by.
            film = centre;
            ok = true;
          } else {
            ok = cam_other.project(p, &film);
          }
        } else if (!camera_moves) {
          film = centre;  // background seen along the same direction
          ok = true;
        } else {
          // Escaped rays see the environment "at infinity": only the direction counts.
          ok = cam_other.project(desc_other.camera.to_world.point(Vec3f(0.0f)) +
                                     ray.d * (0.5f * desc_other.camera.far_clip),
                                 &film);
        }
        if (ok) {
          out.at(x, y, 0) = film.x - centre.x;
          out.at(x, y, 1) = film.y - centre.y;
          out.at(x, y, 2) = 1.0f;
        }
      }
  };
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] { tbb::parallel_for(tbb::blocked_range<int>(0, height, 4), rows); });
  field.rays = uint64_t(width) * uint64_t(height);
  return field;
}

TemporalMask temporal_consistency(const Image& forward, const Image& backward, const TgptSettings& settings) {
  const int w = forward.width(), h = forward.height();
  TemporalMask mask;
  mask.valid.assign(size_t(w) * h, 0);
  mask.failure = Image(w, h, 1);
  const int tol = settings.consistency_tolerance_px;
  const int max_motion = settings.max_same_pixel_motion_px;
  // One direction: p's surface lands at q = p + m(p) in the other frame, and the
  // other frame's field at q must bring it back to p (±tol).
  auto round_trip = [&](const Image& there, const Image& back, int x, int y) {
    if (there.at(x, y, 2) == 0.0f) return false;
    const int mx = motion_pixel_offset(there.at(x, y, 0)), my = motion_pixel_offset(there.at(x, y, 1));
    if (max_motion >= 0 && (std::abs(mx) > max_motion || std::abs(my) > max_motion)) return false;
    const int qx = x + mx, qy = y + my;
    if (qx < 0 || qy < 0 || qx >= w || qy >= h || back.at(qx, qy, 2) == 0.0f) return false;
    return std::abs(mx + motion_pixel_offset(back.at(qx, qy, 0))) <= tol &&
           std::abs(my + motion_pixel_offset(back.at(qx, qy, 1))) <= tol;
  };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool ok = round_trip(forward, backward, x, y) && round_trip(backward, forward, x, y);
      mask.valid[size_t(y) * w + x] = ok ? 1 : 0;
      if (!ok) {
        mask.failure.at(x, y, 0) = 1.0f;
        ++mask.failed;
      }
    }
  return mask;
}

}  // namespace gdvr
