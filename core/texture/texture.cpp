// Texture evaluation with Mitsuba 3's conventions (src/textures/bitmap.cpp,
// checkerboard.cpp). uv is the surface uv; to_uv is applied first.
#include "core/texture/texture.h"

#include <cmath>

namespace gdvr {
namespace {

// Repeat wrap of an integer texel index.
inline int wrap_repeat(int i, int n) {
  int m = i % n;
  return m < 0 ? m + n : m;
}

// Texel index i of a row or column of n under Mitsuba's wrap modes.
inline int wrap_index(int i, int n, TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::kRepeat: return wrap_repeat(i, n);
    case TextureWrap::kClamp: return i < 0 ? 0 : (i >= n ? n - 1 : i);
    case TextureWrap::kMirror: {
      const int m = wrap_repeat(i, 2 * n);
      return m < n ? m : 2 * n - 1 - m;
    }
  }
  return 0;
}

Rgb texel(const Image& img, int x, int y) {
  if (img.channels() >= 3) return img.rgb(x, y);
  return Rgb(img.at(x, y, 0));
}

}  // namespace

Rgb Texture::eval_varying(Vec2f uv_in) const {
  switch (type) {
    case TextureType::kConstant: return value;  // eval() answers this one inline
    case TextureType::kCheckerboard: {
      Vec2f uv = to_uv.apply(uv_in);
      bool mx = uv.x - std::floor(uv.x) > 0.5f, my = uv.y - std::floor(uv.y) > 0.5f;
      // Mitsuba's spectral eval(): color0 where both halves agree.
      return mx == my ? color0 : color1;
    }
    case TextureType::kBitmap: {
      if (!bitmap || bitmap->empty()) return Rgb(0.0f);
      const Image& img = *bitmap;
      const int w = img.width(), h = img.height();
      // Texel centres at (i + 0.5) / res. Row 0 is the image's first (top)
      // row at v = 0: the texture does not flip v. Mitsuba's mesh loaders
      // flip the v of OBJ/PLY/serialized texcoords instead (flip_tex_coords).
      Vec2f uv = to_uv.apply(uv_in);
      if (filter == TextureFilter::kNearest) {
        const float fx = std::floor(uv.x * float(w)), fy = std::floor(uv.y * float(h));
        // Beyond int's range the texel is meaningless; NaN too.
        if (!(std::abs(fx) < 1e9f) || !(std::abs(fy) < 1e9f)) return Rgb(0.0f);
        return texel(img, wrap_index(int(fx), w, wrap), wrap_index(int(fy), h, wrap));
      }
      float x = uv.x * float(w) - 0.5f, y = uv.y * float(h) - 0.5f;
      float fx = std::floor(x), fy = std::floor(y);
      if (!(std::abs(fx) < 1e9f) || !(std::abs(fy) < 1e9f)) return Rgb(0.0f);
      int ix = int(fx), iy = int(fy);
      float w1x = x - fx, w1y = y - fy, w0x = 1.0f - w1x, w0y = 1.0f - w1y;
      int x0 = wrap_index(ix, w, wrap), x1 = wrap_index(ix + 1, w, wrap);
      int y0 = wrap_index(iy, h, wrap), y1 = wrap_index(iy + 1, h, wrap);
      Rgb v0 = texel(img, x0, y0) * w0x + texel(img, x1, y0) * w1x;
      Rgb v1 = texel(img, x0, y1) * w0x + texel(img, x1, y1) * w1x;
      return v0 * w0y + v1 * w1y;
    }
  }
  return Rgb(0.0f);
}

Rgb Texture::mean() const {
  switch (type) {
    case TextureType::kConstant: return value;
    case TextureType::kCheckerboard: return (color0 + color1) * 0.5f;
    case TextureType::kBitmap: {
      if (!bitmap || bitmap->empty()) return Rgb(0.0f);
      double sum[3] = {0, 0, 0};
      for (int y = 0; y < bitmap->height(); ++y)
        for (int x = 0; x < bitmap->width(); ++x) {
          Rgb c = texel(*bitmap, x, y);
          sum[0] += c.r; sum[1] += c.g; sum[2] += c.b;
        }
      double n = double(bitmap->pixel_count());
      return Rgb(float(sum[0] / n), float(sum[1] / n), float(sum[2] / n));
    }
  }
  return Rgb(0.0f);
}

}  // namespace gdvr
