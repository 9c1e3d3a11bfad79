#include "registration/gicp_terms.hpp"

#include <cmath>

#include "geometry/so3.hpp"
#include "registration/point_covariances.hpp"

// The block loops vectorise lane by lane: GCC builds them for each instruction set and the
// loader picks the widest this CPU runs.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && defined(__linux__)
#define TWISTSLAM_GICP_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define TWISTSLAM_GICP_CLONES
#endif

namespace twistslam::registration {

void GicpTerms::reset(int capacity) {
  size_ = 0;
  // whole blocks beyond the last pair, so that pad_to_blocks never reallocates
  const std::size_t room = static_cast<std::size_t>(capacity) + kGicpLanes;
  for (auto& column : columns_)
    if (column.size() < room) column.resize(room);
}

int GicpTerms::pad_to_blocks() {
  const int blocks = (size_ + kGicpLanes - 1) / kGicpLanes;
  for (auto& column : columns_) {
    if (static_cast<int>(column.size()) < blocks * kGicpLanes) column.resize(blocks * kGicpLanes);
    for (int k = size_; k < blocks * kGicpLanes; ++k) column[k] = 0.0;
  }
  return blocks;
}

namespace {

// Per-lane sums: the 21 entries of the rank-two part's upper triangle (row by row), b's six,
// the weights, the weighted moments of q (3 + 6: xx xy xz yy yz zz), e and e x q, the cost and
// |e|^2.
constexpr int kSums = 21 + 6 + 1 + 3 + 6 + 3 + 3 + 1 + 1;

TWISTSLAM_GICP_CLONES void sum_blocks(const GicpTerms& t, int size, int blocks, bool huber,
                                      double threshold, double (*sums)[kGicpLanes]) {
  const double* qx = t.column(0); const double* qy = t.column(1); const double* qz = t.column(2);
  const double* ex = t.column(3); const double* ey = t.column(4); const double* ez = t.column(5);
  const double* nx = t.column(6); const double* ny = t.column(7); const double* nz = t.column(8);
  const double* mx = t.column(9); const double* my = t.column(10); const double* mz = t.column(11);
  // each sum's lanes, by name (rows of `sums`, in the order sum_normal_equations reads)
  double *__restrict h0 = sums[0], *__restrict h1 = sums[1], *__restrict h2 = sums[2],
         *__restrict h3 = sums[3], *__restrict h4 = sums[4], *__restrict h5 = sums[5],
         *__restrict h6 = sums[6], *__restrict h7 = sums[7], *__restrict h8 = sums[8],
         *__restrict h9 = sums[9], *__restrict h10 = sums[10], *__restrict h11 = sums[11],
         *__restrict h12 = sums[12], *__restrict h13 = sums[13], *__restrict h14 = sums[14],
         *__restrict h15 = sums[15], *__restrict h16 = sums[16], *__restrict h17 = sums[17],
         *__restrict h18 = sums[18], *__restrict h19 = sums[19], *__restrict h20 = sums[20],
         *__restrict b0 = sums[21], *__restrict b1 = sums[22], *__restrict b2 = sums[23],
         *__restrict b3 = sums[24], *__restrict b4 = sums[25], *__restrict b5 = sums[26],
         *__restrict w = sums[27], *__restrict q0 = sums[28], *__restrict q1 = sums[29],
         *__restrict q2 = sums[30], *__restrict qq0 = sums[31], *__restrict qq1 = sums[32],
         *__restrict qq2 = sums[33], *__restrict qq3 = sums[34], *__restrict qq4 = sums[35],
         *__restrict qq5 = sums[36], *__restrict e0 = sums[37], *__restrict e1 = sums[38],
         *__restrict e2s = sums[39], *__restrict x0 = sums[40], *__restrict x1 = sums[41],
         *__restrict x2 = sums[42], *__restrict cost = sums[43], *__restrict sse = sums[44];
  for (int block = 0; block < blocks; ++block) {
#pragma omp simd
    for (int l = 0; l < kGicpLanes; ++l) {
      const int k = block * kGicpLanes + l;
      const double valid = k < size ? 1.0 : 0.0;
      const double c = nx[k] * mx[k] + ny[k] * my[k] + nz[k] * mz[k];
      const PlanePairInformation info = plane_pair_information(c);
      const double alpha_sum = info.alpha_sum, alpha_diff = info.alpha_diff;
      const double ux = nx[k] + mx[k], uy = ny[k] + my[k], uz = nz[k] + mz[k];
      const double vx = nx[k] - mx[k], vy = ny[k] - my[k], vz = nz[k] - mz[k];
      const double ue = ux * ex[k] + uy * ey[k] + uz * ez[k];
      const double ve = vx * ex[k] + vy * ey[k] + vz * ez[k];
      const double e2 = ex[k] * ex[k] + ey[k] * ey[k] + ez[k] * ez[k];
      const double m2 = 0.5 * e2 + alpha_sum * ue * ue + alpha_diff * ve * ve;  // e^T W e
      // Huber: a select per lane (computed for every lane, kept where the kernel is on)
      const double r = std::sqrt(m2);
      const bool over = huber && r > threshold;
      const double weight = over ? valid * threshold / r : valid;
      const double rho = over ? valid * threshold * (2.0 * r - threshold) : valid * m2;
      // g = J^T u = [-u; u x q] and the same for v
      const double gu0 = -ux, gu1 = -uy, gu2 = -uz, gu3 = uy * qz[k] - uz * qy[k],
                   gu4 = uz * qx[k] - ux * qz[k], gu5 = ux * qy[k] - uy * qx[k];
      const double gv0 = -vx, gv1 = -vy, gv2 = -vz, gv3 = vy * qz[k] - vz * qy[k],
                   gv4 = vz * qx[k] - vx * qz[k], gv5 = vx * qy[k] - vy * qx[k];
      const double au = weight * alpha_sum, av = weight * alpha_diff;
      const double su0 = au * gu0, su1 = au * gu1, su2 = au * gu2, su3 = au * gu3,
                   su4 = au * gu4, su5 = au * gu5;
      const double sv0 = av * gv0, sv1 = av * gv1, sv2 = av * gv2, sv3 = av * gv3,
                   sv4 = av * gv4, sv5 = av * gv5;
      // the upper triangle row by row (the 21 sums), then b, then the moments
      h0[l] += su0 * gu0 + sv0 * gv0;
      h1[l] += su0 * gu1 + sv0 * gv1;
      h2[l] += su0 * gu2 + sv0 * gv2;
      h3[l] += su0 * gu3 + sv0 * gv3;
      h4[l] += su0 * gu4 + sv0 * gv4;
      h5[l] += su0 * gu5 + sv0 * gv5;
      h6[l] += su1 * gu1 + sv1 * gv1;
      h7[l] += su1 * gu2 + sv1 * gv2;
      h8[l] += su1 * gu3 + sv1 * gv3;
      h9[l] += su1 * gu4 + sv1 * gv4;
      h10[l] += su1 * gu5 + sv1 * gv5;
      h11[l] += su2 * gu2 + sv2 * gv2;
      h12[l] += su2 * gu3 + sv2 * gv3;
      h13[l] += su2 * gu4 + sv2 * gv4;
      h14[l] += su2 * gu5 + sv2 * gv5;
      h15[l] += su3 * gu3 + sv3 * gv3;
      h16[l] += su3 * gu4 + sv3 * gv4;
      h17[l] += su3 * gu5 + sv3 * gv5;
      h18[l] += su4 * gu4 + sv4 * gv4;
      h19[l] += su4 * gu5 + sv4 * gv5;
      h20[l] += su5 * gu5 + sv5 * gv5;
      b0[l] += (au * ue) * gu0 + (av * ve) * gv0;
      b1[l] += (au * ue) * gu1 + (av * ve) * gv1;
      b2[l] += (au * ue) * gu2 + (av * ve) * gv2;
      b3[l] += (au * ue) * gu3 + (av * ve) * gv3;
      b4[l] += (au * ue) * gu4 + (av * ve) * gv4;
      b5[l] += (au * ue) * gu5 + (av * ve) * gv5;
      const double wqx = weight * qx[k], wqy = weight * qy[k], wqz = weight * qz[k];
      w[l] += weight;
      q0[l] += wqx; q1[l] += wqy; q2[l] += wqz;
      qq0[l] += wqx * qx[k]; qq1[l] += wqx * qy[k]; qq2[l] += wqx * qz[k];
      qq3[l] += wqy * qy[k]; qq4[l] += wqy * qz[k]; qq5[l] += wqz * qz[k];
      e0[l] += weight * ex[k]; e1[l] += weight * ey[k]; e2s[l] += weight * ez[k];
      x0[l] += weight * (ey[k] * qz[k] - ez[k] * qy[k]);
      x1[l] += weight * (ez[k] * qx[k] - ex[k] * qz[k]);
      x2[l] += weight * (ex[k] * qy[k] - ey[k] * qx[k]);
      cost[l] += rho;
      sse[l] += valid * e2;
    }
  }
}

}  // namespace

GicpNormalEquations sum_normal_equations(GicpTerms& terms, bool huber, double huber_threshold) {
  const int blocks = terms.pad_to_blocks();
  alignas(64) double sums[kSums][kGicpLanes] = {};
  sum_blocks(terms, terms.size(), blocks, huber, huber_threshold, sums);
  double total[kSums];
  for (int s = 0; s < kSums; ++s) {
    total[s] = 0.0;
    for (int l = 0; l < kGicpLanes; ++l) total[s] += sums[s][l];
  }
  // J^T W J = 0.5 J^T J + the rank-two parts; 0.5 J^T J = [I, -hat(q); hat(q), |q|^2 I - q q^T]
  // summed from the weighted moments of q (gicp.cpp, linearize)
  GicpNormalEquations out;
  int s = 0;
  for (int r = 0; r < 6; ++r)
    for (int c = r; c < 6; ++c, ++s) out.H(r, c) = out.H(c, r) = total[s];
  for (int r = 0; r < 6; ++r, ++s) out.b[r] = total[s];
  const double sum_w = total[s++];
  const Vec3 sum_q(total[s], total[s + 1], total[s + 2]);
  s += 3;
  Mat3 sum_qq;
  sum_qq << total[s], total[s + 1], total[s + 2], total[s + 1], total[s + 3], total[s + 4],
      total[s + 2], total[s + 4], total[s + 5];
  s += 6;
  const Vec3 sum_e(total[s], total[s + 1], total[s + 2]);
  s += 3;
  const Vec3 sum_e_cross_q(total[s], total[s + 1], total[s + 2]);
  s += 3;
  out.cost = total[s++];
  out.sum_squared_error_m2 = total[s];
  const Mat3 hat_sum_q = geometry::hat(sum_q);
  out.H.topLeftCorner<3, 3>().diagonal().array() += 0.5 * sum_w;
  out.H.topRightCorner<3, 3>() -= 0.5 * hat_sum_q;
  out.H.bottomLeftCorner<3, 3>() += 0.5 * hat_sum_q;
  out.H.bottomRightCorner<3, 3>() += 0.5 * (sum_qq.trace() * Mat3::Identity() - sum_qq);
  out.b.head<3>() -= 0.5 * sum_e;
  out.b.tail<3>() += 0.5 * sum_e_cross_q;
  return out;
}

}  // namespace twistslam::registration
