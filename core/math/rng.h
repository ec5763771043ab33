// Deterministic random numbers. Every sample's stream is a pure function of
// (seed, frame, pixel, sample index), so images do not depend on thread count or
// tile order, and a gradient-domain offset can replay a base path's numbers.
#pragma once

#include <cstdint>

#include "core/math/vec.h"

namespace gdvr {

// 64-bit mix (splitmix64 finaliser): turns structured keys into well-spread seeds.
inline uint64_t mix64(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

inline uint64_t hash_combine(uint64_t a, uint64_t b) { return mix64(a ^ (mix64(b) + 0x9e3779b97f4a7c15ULL)); }

// PCG32 (O'Neill 2014): small state, good statistics, cheap to seed per sample.
class Pcg32 {
 public:
  Pcg32() { seed(0x853c49e6748fea9bULL, 0xda3e39cb94b95bdbULL); }
  Pcg32(uint64_t state, uint64_t stream) { seed(state, stream); }

  void seed(uint64_t init_state, uint64_t init_stream) {
    state_ = 0;
    inc_ = (init_stream << 1u) | 1u;
    next_u32();
    state_ += init_state;
    next_u32();
  }
  uint32_t next_u32() {
    uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = static_cast<uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
  }
  // Uniform in [0, 1): 24 random mantissa bits, never returns 1.
  float next_float() { return static_cast<float>(next_u32() >> 8) * 0x1p-24f; }

  // The generator's two words, for code that advances many generators at
  // once in vector registers (vector_batch.cpp) and hands them back.
  uint64_t state() const { return state_; }
  uint64_t increment() const { return inc_; }
  void restore(uint64_t state, uint64_t increment) {
    state_ = state;
    inc_ = increment;
  }

 private:
  uint64_t state_ = 0, inc_ = 0;
};

// The sample stream of one (seed, frame, pixel, sample) tuple.
class Sampler {
 public:
  Sampler() = default;
  Sampler(uint64_t seed, uint32_t frame, uint32_t px, uint32_t py, uint32_t sample_index)
      : Sampler(PixelKey(seed, frame, px, py), sample_index) {}

  // What every sample of one pixel shares: hashed once per pixel by a loop
  // over its samples (five of a sample's seven mixes).
  struct PixelKey {
    PixelKey(uint64_t seed, uint32_t frame, uint32_t px, uint32_t py)
        : key(hash_combine(hash_combine(seed, frame), (uint64_t(py) << 32) | px)), stream(mix64(key)) {}
    uint64_t key, stream;
  };
  Sampler(const PixelKey& pixel, uint32_t sample_index) { rng_.seed(hash_combine(pixel.key, sample_index), pixel.stream); }

  float next_1d() { return rng_.next_float(); }
  Vec2f next_2d() {
    float a = next_1d();
    return {a, next_1d()};
  }
  Pcg32& generator() { return rng_; }
  const Pcg32& generator() const { return rng_; }

 private:
  Pcg32 rng_;
};

}  // namespace gdvr
