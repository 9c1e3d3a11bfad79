#include "registration/smallest_eigenvectors.hpp"

#include <cmath>

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__)
#define TWISTSLAM_EIGEN_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define TWISTSLAM_EIGEN_CLONES
#endif

namespace twistslam::registration {

namespace {

constexpr int kLanes = 8;

// The matrices' normalised forms and Newton's progress, one coordinate array each (padded to
// whole blocks).
struct Work {
  // b (6), det, x, then 1 / 0 flags: isotropic, moving
  enum Column { kB00, kB01, kB02, kB11, kB12, kB22, kDet, kX, kIsotropic, kMoving, kColumns };
  std::vector<double> columns[kColumns];
  explicit Work(std::size_t n) {
    for (auto& c : columns) c.resize(n);
  }
  double* operator[](int c) { return columns[c].data(); }
  const double* operator[](int c) const { return columns[c].data(); }
};

// One Newton step of x^3 - 3x - det from x, as every lane takes it: x moves when the step goes
// right (from the left of the root, f < 0 and f' > 0); else the lane stops for good.
inline void newton_step(double det, double* x, bool* moving) {
  const double f = *x * *x * *x - 3.0 * *x - det, df = 3.0 * *x * *x - 3.0;
  const double next = *x - f / df;  // not used where df <= 0
  const bool move = *moving && df > 0.0 && !(f >= 0.0) && next > *x;
  *x = move ? next : *x;
  *moving = move;
}

TWISTSLAM_EIGEN_CLONES void normalise_and_start(const SymmetricMatrices& m, int blocks, Work* w) {
  const double *a00 = m.a00.data(), *a01 = m.a01.data(), *a02 = m.a02.data();
  const double *a11 = m.a11.data(), *a12 = m.a12.data(), *a22 = m.a22.data();
  double *__restrict o00 = (*w)[Work::kB00], *__restrict o01 = (*w)[Work::kB01],
         *__restrict o02 = (*w)[Work::kB02], *__restrict o11 = (*w)[Work::kB11],
         *__restrict o12 = (*w)[Work::kB12], *__restrict o22 = (*w)[Work::kB22],
         *__restrict odet = (*w)[Work::kDet], *__restrict ox = (*w)[Work::kX],
         *__restrict oiso = (*w)[Work::kIsotropic], *__restrict omov = (*w)[Work::kMoving];
  for (int block = 0; block < blocks; ++block) {
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      const int k = block * kLanes + l;
      const double shift = (a00[k] + a11[k] + a22[k]) / 3.0;
      double b00 = a00[k] - shift, b11 = a11[k] - shift, b22 = a22[k] - shift;
      double b01 = a01[k], b02 = a02[k], b12 = a12[k];
      const double p2 = (b00 * b00 + b11 * b11 + b22 * b22 +
                         2.0 * (b01 * b01 + b02 * b02 + b12 * b12)) / 6.0;  // tr(B^2) / 6
      const bool isotropic = !(p2 > 0.0);
      const double s = std::sqrt(isotropic ? 1.0 : p2);
      b00 /= s, b01 /= s, b02 /= s, b11 /= s, b12 /= s, b22 /= s;
      const double det = b00 * (b11 * b22 - b12 * b12) - b01 * (b01 * b22 - b12 * b02) +
                         b02 * (b01 * b12 - b11 * b02);
      double x = -2.0;
      bool moving = !isotropic;
      for (int step = 0; step < kBlockNewtonSteps; ++step) newton_step(det, &x, &moving);
      o00[k] = b00, o01[k] = b01, o02[k] = b02, o11[k] = b11, o12[k] = b12, o22[k] = b22;
      odet[k] = det, ox[k] = x;
      oiso[k] = isotropic ? 1.0 : 0.0, omov[k] = moving ? 1.0 : 0.0;
    }
  }
}

TWISTSLAM_EIGEN_CLONES void eigenvectors(const Work& w, int blocks, double* __restrict nx,
                                         double* __restrict ny, double* __restrict nz) {
  const double *b00 = w[Work::kB00], *b01 = w[Work::kB01], *b02 = w[Work::kB02];
  const double *b11 = w[Work::kB11], *b12 = w[Work::kB12], *b22 = w[Work::kB22];
  const double *xs = w[Work::kX], *iso = w[Work::kIsotropic];
  for (int block = 0; block < blocks; ++block) {
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      const int k = block * kLanes + l;
      // the rows of B - x I: (r00 r01 r02), (r01 r11 r12), (r02 r12 r22)
      const double r00 = b00[k] - xs[k], r01 = b01[k], r02 = b02[k];
      const double r11 = b11[k] - xs[k], r12 = b12[k], r22 = b22[k] - xs[k];
      // row 0 x row 1, row 0 x row 2, row 1 x row 2
      const double c01x = r01 * r12 - r02 * r11, c01y = r02 * r01 - r00 * r12,
                   c01z = r00 * r11 - r01 * r01;
      const double c02x = r01 * r22 - r02 * r12, c02y = r02 * r02 - r00 * r22,
                   c02z = r00 * r12 - r01 * r02;
      const double c12x = r11 * r22 - r12 * r12, c12y = r12 * r02 - r01 * r22,
                   c12z = r01 * r12 - r11 * r02;
      const double n01 = c01x * c01x + c01y * c01y + c01z * c01z;
      const double n02 = c02x * c02x + c02y * c02y + c02z * c02z;
      const double n12 = c12x * c12x + c12y * c12y + c12z * c12z;
      // the largest of the three (the first of equals), as long as it is not zero
      const bool use01 = n01 >= n02 && n01 >= n12 && n01 > 0.0;
      const bool use02 = !use01 && n02 >= n12 && n02 > 0.0;
      const bool use12 = !use01 && !use02 && n12 > 0.0;
      const bool none = iso[k] != 0.0 || !(use01 || use02 || use12);
      const double cx = use01 ? c01x : (use02 ? c02x : c12x);
      const double cy = use01 ? c01y : (use02 ? c02y : c12y);
      const double cz = use01 ? c01z : (use02 ? c02z : c12z);
      const double norm = std::sqrt(none ? 1.0 : (use01 ? n01 : (use02 ? n02 : n12)));
      nx[k] = none ? 1.0 : cx / norm;
      ny[k] = none ? 0.0 : cy / norm;
      nz[k] = none ? 0.0 : cz / norm;
    }
  }
}

}  // namespace

std::vector<Vec3> smallest_eigenvectors(const SymmetricMatrices& matrices) {
  const int n = static_cast<int>(matrices.size());
  const int blocks = (n + kLanes - 1) / kLanes;
  const std::size_t padded = static_cast<std::size_t>(blocks) * kLanes;
  SymmetricMatrices m = matrices;  // padded with zero (isotropic) matrices
  m.resize(padded);
  Work w(padded);
  normalise_and_start(m, blocks, &w);
  for (int k = 0; k < n; ++k) {  // the few still moving: one by one, as far as a lane would go
    if (w[Work::kMoving][k] == 0.0) continue;
    bool moving = true;
    for (int step = kBlockNewtonSteps; step < kMaxNewtonSteps && moving; ++step)
      newton_step(w[Work::kDet][k], &w[Work::kX][k], &moving);
  }
  std::vector<double> nx(padded), ny(padded), nz(padded);
  eigenvectors(w, blocks, nx.data(), ny.data(), nz.data());
  std::vector<Vec3> normals(n);
  for (int k = 0; k < n; ++k) normals[k] = Vec3(nx[k], ny[k], nz[k]);
  return normals;
}

}  // namespace twistslam::registration
