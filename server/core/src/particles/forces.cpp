// Sum of the pair potentials, one fused kernel per unordered neighbour pair (i < j), and the stable time
// step from the summed stiffness bounds.
//
// Order of the sums (so that results do not depend on the thread count): for particle i,
//   total_i = upper_i + lower_i,
// upper_i the sum over its neighbours j > i in ascending j as four lane partial sums combined in a fixed
// order (force_rows), lower_i the sum (from zero) over its neighbours k < i in ascending k of what pair (k, i)
// gives i. One thread adds lower_i while visiting the rows in
// ascending order; several threads store each pair's share for its upper particle and gather it afterwards.
// Both evaluate the same expressions in the same order, so the bits are the same (forces.cpp is compiled
// without floating-point contraction, so an inlined expression cannot become an FMA in one path only).
#include "surfeledit/core/particles/forces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pair_kernel.hpp"
#include "surfeledit/core/util.hpp"

namespace surfeledit {

namespace {

using namespace fused_pairs;

// The pair loop is compiled once per instruction set (force_rows_* below; each inlines the kernels) and
// picked at run time. Without contraction (see above) every lane computes the same IEEE operations at any
// vector width, so every variant gives the same bits (tested).
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define SURFELEDIT_FORCE_AVX2 1
#endif
// The helpers below are always inlined, so the ABI of passing vectors does not matter (GCC warns without AVX).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
// Four doubles as one value (GCC / Clang vector extension): a ymm register in the AVX2 variant, two xmm
// registers otherwise; the same IEEE operation per element either way. V4u reads and writes unaligned memory.
using V4 = double __attribute__((vector_size(32)));
using V4u = double __attribute__((vector_size(32), aligned(8), may_alias));
[[gnu::always_inline]] inline V4 load4(const double* p) { return *reinterpret_cast<const V4u*>(p); }
[[gnu::always_inline]] inline void store4(double* p, V4 v) { *reinterpret_cast<V4u*>(p) = v; }
// Rows (a, b, c, d) -> columns: afterwards a = (a0 b0 c0 d0), b = (a1 b1 c1 d1), ...
[[gnu::always_inline]] inline void transpose(V4& a, V4& b, V4& c, V4& d) {
  const V4 t0 = __builtin_shufflevector(a, b, 0, 4, 2, 6), t1 = __builtin_shufflevector(a, b, 1, 5, 3, 7);
  const V4 t2 = __builtin_shufflevector(c, d, 0, 4, 2, 6), t3 = __builtin_shufflevector(c, d, 1, 5, 3, 7);
  a = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
  b = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
  c = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
  d = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}
// (v0 + v1) + (v2 + v3): the fixed order in which a row's four partial sums are combined.
[[gnu::always_inline]] inline double lane_sum(V4 v) { return (v[0] + v[1]) + (v[2] + v[3]); }

// First entry of row i with a neighbour above i (rows ascending).
inline std::int64_t upper_begin(const Neighbourhood& nb, Index i) {
  const auto begin = nb.indices.begin();
  return std::upper_bound(begin + nb.offsets[i], begin + nb.offsets[i + 1], i) - begin;
}

// What the row pass reads and writes. Records are 8 doubles: a particle's (x, y, z, 0, nx, ny, nz, 0), and a
// pair's share for its lower particle j (-f_x, -f_y, -f_z, k, t_jx, t_jy, t_jz, 0).
struct RowPass {
  const ParticleParams* p;
  const Neighbourhood* nb;
  const double* particles;  // #P + 1 particle records; record #P is the padding lanes' (never read back)
  bool compact;             // the one-pass kernel applies
  // threads == 1: `lower` holds #P + 1 running sums of the shares (record #P takes the padding lanes), and
  // row i writes upper_i + lower_i. Otherwise each pair's share goes to `shares` at its entry (#E records)
  // and row i writes upper_i only.
  double* lower;
  double* shares;
  double* force;      // #P by 3
  double* torque;     // #P by 3
  double* stiffness;  // #P
  double* energy;     // #P: the upper sum of E_ij
};

// Rows [begin, end): every upper pair through the kernel in blocks, four lanes at a time moved between the
// particle / share records and the block's arrays by 4 x 4 transposes (one vector load or store per record
// instead of a scalar one per coordinate). upper_i = its four lanes' partial sums in ascending order of
// blocks, combined by lane_sum; the padding lanes add zeros.
static_assert(kPad == 4, "force_rows moves lanes in groups of four");
SURFELEDIT_INLINE void force_rows(const RowPass& rp, Index begin, Index end, PairBlock& b) {
  const Neighbourhood& nb = *rp.nb;
  const Index n = nb.size();
  const double far = 2.0 * rp.p->weight.radius;  // padding lanes: out of range, so they give zeros
  const Index* indices = nb.indices.data();
  double* const lower = rp.lower;  // locals: stores through double* would make the compiler reload them
  double* const shares = rp.shares;
  const double* const particles = rp.particles;
  for (Index i = begin; i < end; ++i) {
    const double* xi = particles + 8 * i;
    const Vec3 ni(xi[4], xi[5], xi[6]);
    const V4 zero = {0.0, 0.0, 0.0, 0.0};
    V4 fx = zero, fy = zero, fz = zero, tx = zero, ty = zero, tz = zero, k = zero, e = zero;
    for (std::int64_t c0 = upper_begin(nb, i), row_end = nb.offsets[i + 1]; c0 < row_end; c0 += kLanes) {
      const int count = static_cast<int>(std::min<std::int64_t>(kLanes, row_end - c0));
      const Index* js = indices + c0;
      b.size = (count + kPad - 1) / kPad * kPad;  // whole vectors: a scalar remainder costs several vectors
      for (int l = 0; l < b.size; l += 4) {
        const double* r[4];
        for (int q = 0; q < 4; ++q) r[q] = particles + 8 * (l + q < count ? js[l + q] : n);
        V4 x0 = load4(r[0]), x1 = load4(r[1]), x2 = load4(r[2]), x3 = load4(r[3]);
        V4 n0 = load4(r[0] + 4), n1 = load4(r[1] + 4), n2 = load4(r[2] + 4), n3 = load4(r[3] + 4);
        transpose(x0, x1, x2, x3);
        transpose(n0, n1, n2, n3);
        store4(b.rx + l, x0 - xi[0]), store4(b.ry + l, x1 - xi[1]), store4(b.rz + l, x2 - xi[2]);
        store4(b.njx + l, n0), store4(b.njy + l, n1), store4(b.njz + l, n2);
      }
      for (int l = count; l < b.size; ++l) {
        b.rx[l] = far, b.ry[l] = 0.0, b.rz[l] = 0.0;
        b.njx[l] = 0.0, b.njy[l] = 0.0, b.njz[l] = 1.0;
      }
      if (rp.compact) {
        compact_kernel(*rp.p, ni, b);
      } else {
        radial_terms(*rp.p, b);
        pair_kernel(*rp.p, ni, b);
      }
      for (int l = 0; l < b.size; l += 4) {
        const V4 gx = load4(b.fx + l), gy = load4(b.fy + l), gz = load4(b.fz + l), gk = load4(b.k + l);
        const V4 tjx = load4(b.tjx + l), tjy = load4(b.tjy + l), tjz = load4(b.tjz + l);
        fx += gx, fy += gy, fz += gz, k += gk, e += load4(b.e + l);
        tx += load4(b.tix + l), ty += load4(b.tiy + l), tz += load4(b.tiz + l);
        V4 s0 = -gx, s1 = -gy, s2 = -gz, s3 = gk, u0 = tjx, u1 = tjy, u2 = tjz, u3 = zero;
        transpose(s0, s1, s2, s3);
        transpose(u0, u1, u2, u3);
        const V4 share_f[4] = {s0, s1, s2, s3}, share_t[4] = {u0, u1, u2, u3};
        for (int q = 0; q < 4; ++q) {
          const bool real = l + q < count;
          if (lower) {
            double* acc = lower + 8 * (real ? js[l + q] : n);
            store4(acc, load4(acc) + share_f[q]);
            store4(acc + 4, load4(acc + 4) + share_t[q]);
          } else if (real) {  // threads share no padding record
            double* out = shares + 8 * (c0 + l + q);
            store4(out, share_f[q]);
            store4(out + 4, share_t[q]);
          }
        }
      }
    }
    double up[8] = {lane_sum(fx), lane_sum(fy), lane_sum(fz), lane_sum(k),
                    lane_sum(tx), lane_sum(ty), lane_sum(tz), 0.0};
    if (lower) {  // lower_i is complete: every row below i is done
      const double* lo = lower + 8 * i;
      for (int c = 0; c < 8; ++c) up[c] = up[c] + lo[c];
    }
    rp.force[3 * i] = up[0], rp.force[3 * i + 1] = up[1], rp.force[3 * i + 2] = up[2];
    rp.stiffness[i] = up[3];
    rp.torque[3 * i] = up[4], rp.torque[3 * i + 1] = up[5], rp.torque[3 * i + 2] = up[6];
    rp.energy[i] = lane_sum(e);
  }
}

// The compiled variants of force_rows.
void force_rows_baseline(const RowPass& rp, Index begin, Index end, PairBlock& b) { force_rows(rp, begin, end, b); }
#ifdef SURFELEDIT_FORCE_AVX2
__attribute__((target("avx2"))) void force_rows_avx2(const RowPass& rp, Index begin, Index end, PairBlock& b) {
  force_rows(rp, begin, end, b);
}
#endif
using RowsFn = void (*)(const RowPass&, Index, Index, PairBlock&);
RowsFn rows_variant(ForcePath path) {
#ifdef SURFELEDIT_FORCE_AVX2
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (path == ForcePath::Avx2 && !avx2) throw Error(ErrorCode::Conflict, "path", "this CPU has no AVX2");
  if (path == ForcePath::Avx2 || (path == ForcePath::Auto && avx2)) return force_rows_avx2;
#else
  if (path == ForcePath::Avx2) throw Error(ErrorCode::Conflict, "path", "built without the AVX2 variant");
#endif
  return force_rows_baseline;
}

}  // namespace

bool force_path_available(ForcePath path) {
#ifdef SURFELEDIT_FORCE_AVX2
  return path != ForcePath::Avx2 || __builtin_cpu_supports("avx2");
#else
  return path != ForcePath::Avx2;
#endif
}

void compute_forces(const ParticleState& s, const Neighbourhood& nb, const ParticleParams& p, SystemForces& out,
                    ForcePath path) {
  const RowsFn force_rows_variant = rows_variant(path);
  const Index n = s.size();
  if (nb.size() != n) throw Error(ErrorCode::InvalidArgument, "neighbourhood", "one row per particle expected");
  out.force.resize(n, 3);
  out.torque.resize(n, 3);
  out.stiffness.resize(n);
  out.pair_energy.resize(n);
  std::vector<double>& rec = out.particles;
  rec.resize(8 * static_cast<std::size_t>(n + 1));
  for (Index i = 0; i < n; ++i) {
    const Vec3 ni = s.normal(i);
    double* r = rec.data() + 8 * i;
    r[0] = s.x(i, 0), r[1] = s.x(i, 1), r[2] = s.x(i, 2), r[3] = 0.0;
    r[4] = ni.x(), r[5] = ni.y(), r[6] = ni.z(), r[7] = 0.0;
  }
  std::fill_n(rec.data() + 8 * n, 8, 0.0);
  rec[8 * n + 6] = 1.0;  // the padding record: a unit normal
  const int threads = resolve_threads(p.threads);

  RowPass rp{};
  rp.p = &p;
  rp.nb = &nb;
  rp.particles = rec.data();
  rp.compact = p.weight.kind == WeightKind::Compact &&
               (p.repulsion.kind == RepulsionKind::Weight || p.repulsion.kind == RepulsionKind::None);
  rp.force = out.force.data();
  rp.torque = out.torque.data();
  rp.stiffness = out.stiffness.data();
  rp.energy = out.pair_energy.data();

  if (threads == 1) {
    out.lower.assign(8 * static_cast<std::size_t>(n + 1), 0.0);
    rp.lower = out.lower.data();
    PairBlock b;
    force_rows_variant(rp, 0, n, b);
  } else {
    // mirror[c] of a lower entry (row j, neighbour k < j) is the entry of j in row k.
    const std::size_t entries = nb.indices.size();
    out.shares.resize(8 * entries);  // every upper entry is written before it is read
    rp.shares = out.shares.data();
    std::vector<std::int64_t>& mirror = out.mirror;
    mirror.assign(entries, 0);
    std::vector<std::int64_t> cursor(nb.offsets.begin(), nb.offsets.end() - 1);
    for (Index i = 0; i < n; ++i)
      for (std::int64_t c = upper_begin(nb, i); c < nb.offsets[i + 1]; ++c) {
        const Index j = nb.indices[c];
        if (cursor[j] >= nb.offsets[j + 1] || nb.indices[cursor[j]] != i)
          throw Error(ErrorCode::InvalidArgument, "neighbourhood", "not symmetric: j in N(i) but i not in N(j)");
        mirror[cursor[j]++] = c;
      }
    for (Index j = 0; j < n; ++j)
      if (cursor[j] != upper_begin(nb, j))
        throw Error(ErrorCode::InvalidArgument, "neighbourhood", "not symmetric: i in N(j) but j not in N(i)");
    const double* shares = out.shares.data();
#pragma omp parallel num_threads(threads)
    {
      PairBlock b;
      const Index chunk = (n + threads - 1) / threads;
#pragma omp for schedule(static)
      for (int t = 0; t < threads; ++t)
        force_rows_variant(rp, std::min<Index>(n, t * chunk), std::min<Index>(n, (t + 1) * chunk), b);
#pragma omp for schedule(static)
      for (Index j = 0; j < n; ++j) {
        // lower_j: the shares of its lower entries, in ascending order, summed from zero as one thread does.
        V4 f = {0.0, 0.0, 0.0, 0.0}, tq = f;
        for (std::int64_t c = nb.offsets[j]; c < nb.offsets[j + 1] && nb.indices[c] < j; ++c) {
          f = f + load4(shares + 8 * mirror[c]);
          tq = tq + load4(shares + 8 * mirror[c] + 4);
        }
        for (int c = 0; c < 3; ++c) {
          out.force(j, c) = out.force(j, c) + f[c];
          out.torque(j, c) = out.torque(j, c) + tq[c];
        }
        out.stiffness[j] = out.stiffness[j] + f[3];
      }
    }
  }
  out.energy = out.pair_energy.sum();
}

double stable_time_step(const SystemForces& forces, const Values& scale, const ParticleParams& p) {
  double lambda = 0.0, s_max = 0.0;
  for (Eigen::Index i = 0; i < forces.stiffness.size(); ++i) {
    lambda = std::max(lambda, 2.0 * scale[i] * forces.stiffness[i]);
    s_max = std::max(s_max, scale[i]);
  }
  const double b = s_max * std::max(p.damping, p.angular_damping);
  if (lambda == 0.0 && b == 0.0) return std::numeric_limits<double>::infinity();
  // Damped symplectic step x'' = -lambda x - b x' is stable for lambda h^2 + 2 b h < 4.
  return p.dt_safety * 4.0 / (b + std::sqrt(b * b + 4.0 * lambda));
}

}  // namespace surfeledit
