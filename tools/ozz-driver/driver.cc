// Times ozz-animation 0.16.0's C++ SkinningJob (4 influences, positions + normals, no
// inverse-transpose palette) on data written by keyrig's deformer_timing example
// (KEYRIG_SKIN_DUMP=DIR). Prints the minimum over ROUNDS runs in ns per vertex and the largest
// difference from keyrig's linear blend positions. Build and run: docs/skinning-vs-ozz.md.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>
#include "ozz/base/maths/simd_math.h"
#include "ozz/geometry/runtime/skinning_job.h"

template <class T>
static std::vector<T> load(const std::string& path) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) { std::fprintf(stderr, "cannot read %s\n", path.c_str()); std::exit(1); }
  size_t bytes = f.tellg();
  f.seekg(0);
  std::vector<T> v(bytes / sizeof(T));
  f.read(reinterpret_cast<char*>(v.data()), bytes);
  return v;
}

int main(int argc, char** argv) {
  if (argc < 3) { std::fprintf(stderr, "driver DIR ROUNDS\n"); return 1; }
  std::string dir = argv[1];
  int rounds = std::atoi(argv[2]);
  auto palette_f = load<float>(dir + "/palette.f32");      // 16 floats per joint, column-major
  auto indices = load<uint16_t>(dir + "/joints.u16");      // 4 per vertex
  auto weights = load<float>(dir + "/weights3.f32");       // 3 per vertex
  auto positions = load<float>(dir + "/positions.f32");    // 3 per vertex
  auto normals = load<float>(dir + "/normals.f32");        // 3 per vertex
  size_t joints = palette_f.size() / 16;
  int n = int(positions.size() / 3);
  std::vector<ozz::math::Float4x4> palette(joints);
  for (size_t j = 0; j < joints; ++j) {
    for (int c = 0; c < 4; ++c) {
      const float* p = &palette_f[16 * j + 4 * c];
      palette[j].cols[c] = ozz::math::simd_float4::Load(p[0], p[1], p[2], p[3]);
    }
  }
  std::vector<float> out_p(3 * size_t(n)), out_n(3 * size_t(n));
  ozz::geometry::SkinningJob job;
  job.vertex_count = n;
  job.influences_count = 4;
  job.joint_matrices = ozz::make_span(palette);
  job.joint_indices = ozz::make_span(indices);
  job.joint_indices_stride = sizeof(uint16_t) * 4;
  job.joint_weights = ozz::make_span(weights);
  job.joint_weights_stride = sizeof(float) * 3;
  job.in_positions = ozz::make_span(positions);
  job.in_positions_stride = sizeof(float) * 3;
  job.in_normals = ozz::make_span(normals);
  job.in_normals_stride = sizeof(float) * 3;
  job.out_positions = ozz::make_span(out_p);
  job.out_positions_stride = sizeof(float) * 3;
  job.out_normals = ozz::make_span(out_n);
  job.out_normals_stride = sizeof(float) * 3;
  if (!job.Validate()) { std::fprintf(stderr, "invalid job\n"); return 1; }
  double best = 1e30;
  for (int r = 0; r < rounds; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    job.Run();
    auto t1 = std::chrono::steady_clock::now();
    asm volatile("" : : "r"(out_p.data()), "r"(out_n.data()) : "memory");
    best = std::min(best, std::chrono::duration<double>(t1 - t0).count());
  }
  // Check against keyrig's output (written by the example) when present.
  std::ifstream ref(dir + "/keyrig_positions.f32");
  if (ref) {
    auto kp = load<float>(dir + "/keyrig_positions.f32");
    double worst = 0;
    for (size_t i = 0; i < kp.size() && i < out_p.size(); ++i) worst = std::max(worst, double(std::abs(kp[i] - out_p[i])));
    std::printf("ozz_cpp %d vertices: %.3f ms  %.3f ns/vertex  (max |ozz - keyrig| position %.2e)\n", n, best * 1e3, best * 1e9 / n, worst);
  } else {
    std::printf("ozz_cpp %d vertices: %.3f ms  %.3f ns/vertex\n", n, best * 1e3, best * 1e9 / n);
  }
  return 0;
}
