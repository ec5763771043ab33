// Textures as Mitsuba 3 defines them: a constant colour, a bitmap (bilinear
// or nearest, repeat, mirror or clamp wrap, PNG/JPEG decoded from sRGB to
// linear, EXR linear), or a checkerboard. Evaluated at a surface uv, after the texture's to_uv transform.
#pragma once

#include <memory>

#include "core/image/image.h"
#include "core/math/vec.h"

namespace gdvr {

enum class TextureType { kConstant, kBitmap, kCheckerboard };
enum class TextureFilter { kBilinear, kNearest };
enum class TextureWrap { kRepeat, kMirror, kClamp };

// 2D affine uv transform: uv' = (a*u + b*v + c, d*u + e*v + f).
struct UvTransform {
  float a = 1, b = 0, c = 0, d = 0, e = 1, f = 0;
  Vec2f apply(Vec2f uv) const { return {a * uv.x + b * uv.y + c, d * uv.x + e * uv.y + f}; }
  bool is_identity() const { return a == 1 && b == 0 && c == 0 && d == 0 && e == 1 && f == 0; }
};

struct Texture {
  TextureType type = TextureType::kConstant;
  Rgb value{0.5f};                        // kConstant
  std::shared_ptr<const Image> bitmap;    // kBitmap: linear RGB, 3 channels
  TextureFilter filter = TextureFilter::kBilinear;  // kBitmap
  TextureWrap wrap = TextureWrap::kRepeat;          // kBitmap
  Rgb color0{0.4f}, color1{0.2f};         // kCheckerboard (Mitsuba defaults)
  UvTransform to_uv;

  static Texture constant(Rgb c) {
    Texture t;
    t.value = c;
    return t;
  }
  bool is_constant() const { return type == TextureType::kConstant; }
  // Inline for the constant case: most BSDF parameters are constants, and a
  // call per evaluation was a tenth of a diffuse bounce's instructions.
  Rgb eval(Vec2f uv) const { return type == TextureType::kConstant ? value : eval_varying(uv); }
  // Mean over the texture's domain (for albedo estimates and lobe selection).
  Rgb mean() const;
  // eval() of a bitmap or checkerboard, out of line: what the vector kernels
  // call per lane (they call no inline code of the rest of gdvr).
  Rgb eval_varying(Vec2f uv) const;
};

}  // namespace gdvr
