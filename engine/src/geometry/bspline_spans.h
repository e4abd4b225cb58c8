#pragma once
// B-spline surface points from each knot span's polynomial, built once per span, bit for bit as
// OCCT's adaptor computes them (SpanPolynomials), and the knot span lookup they share with the
// B-spline normals of OcctSurface (KnotSpan). Internal to geometry/surface.cpp.
#include <BSplSLib.hxx>
#include <Geom_BSplineSurface.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <unordered_map>
#include <vector>

#include "core/geom.h"

namespace rdmesh {

// The knot span [k[i-1], k[i]) of the distinct knots k holding t, i in [1, size - 1], the first
// and last open-ended, into *lo, *hi; returns i. A (periodically normalised) parameter's span, as
// both B-spline evaluators of OcctSurface take it.
inline int KnotSpan(const std::vector<double>& k, double t, double* lo, double* hi) {
  const int last = static_cast<int>(k.size()) - 1;
  int i = static_cast<int>(std::upper_bound(k.begin(), k.end(), t) - k.begin());
  i = std::clamp(i, 1, std::max(last, 1));
  *lo = i > 1 ? k[i - 1] : -HUGE_VAL;
  *hi = i < last ? k[i] : HUGE_VAL;
  return i;
}

// S(u,v) of a B-spline surface, computed as OCCT's adaptor does it, bit for bit: BSplSLib_Cache's
// Taylor coefficients of the knot span (built by BSplSLib::BuildCache), evaluated by Horner's rule
// along the direction of higher degree, then the other (BSplSLib_Cache::D0 with
// PLib::NoDerivativeEvalPolynomial). Without the adaptor's dispatch, its cache handle and the
// library's general polynomial loops; and each span's coefficients are built once, when a point
// first falls in it, and kept (an adaptor keeps one span and rebuilds it whenever a point falls in
// another, which refinement does all the time: a triangle's samples straddle knot lines). Which
// span a point takes depends on the point alone: [k_i, k_i+1) of the distinct knots after
// periodic normalisation, the first and last spans open-ended. (An adaptor answers a point on a
// knot line, or an ulp below it, from the span it built last, if that one holds it: there the
// two may differ in the last bits.)
class SpanPolynomials {
 public:
  explicit SpanPolynomials(const Geom_BSplineSurface& s)
      : u_(s.UDegree(), s.IsUPeriodic(), s.UKnotSequence()),
        v_(s.VDegree(), s.IsVPeriodic(), s.VKnotSequence()),
        dimension_(s.Weights() ? 4 : 3),
        size_(dimension_ * (std::max(u_.Degree, v_.Degree) + 1) *
              (std::min(u_.Degree, v_.Degree) + 1)) {
    const int minor = std::min(u_.Degree, v_.Degree);
    if (minor >= 1 && minor <= 3) {
      using Fn = decltype(horner_);
      static constexpr Fn kFixed[2][3] = {{Horner<3, 1>, Horner<3, 2>, Horner<3, 3>},
                                          {Horner<4, 1>, Horner<4, 2>, Horner<4, 3>}};
      horner_ = kFixed[dimension_ - 3][minor - 1];
    }
  }

  // (u, v) periodically normalised as BSplSLib_Cache does it.
  void Normalize(double* u, double* v) const {
    *u = u_.PeriodicNormalization(*u), *v = v_.PeriodicNormalization(*v);
  }

  // `uknots`, `vknots`: the surface's distinct knots (Surface::uknots.at, vknots.at).
  Vec3 Value(const Geom_BSplineSurface& s, const std::vector<double>& uknots,
             const std::vector<double>& vknots, double u, double v) {
    double nu = u, nv = v;
    Normalize(&nu, &nv);
    // Consecutive points mostly share a span, or fall in the one before it (samples on either
    // side of a knot line): the last two are tried first.
    auto holds = [nu, nv](const Span* sp) {
      return sp && sp->lo_u <= nu && nu < sp->hi_u && sp->lo_v <= nv && nv < sp->hi_v;
    };
    const Span* span = last_;
    if (!holds(span)) {
      span = holds(previous_) ? previous_ : &Find(s, uknots, vknots, nu, nv);
      previous_ = last_, last_ = span;
    }
    // Parameters local to the span: BSplSLib centres it, with half its length as unit.
    double lu = (nu - span->start_u) / span->half_u;
    double lv = (nv - span->start_v) / span->half_v;
    const bool u_major = u_.Degree > v_.Degree;
    const int major = u_major ? u_.Degree : v_.Degree, minor = u_major ? v_.Degree : u_.Degree;
    double r[4];
    horner_(&coeffs_[span->offset], major, minor, dimension_, u_major ? lu : lv, u_major ? lv : lu,
            r);
    if (dimension_ == 4) r[0] /= r[3], r[1] /= r[3], r[2] /= r[3];
    return {r[0], r[1], r[2]};
  }

 private:
  struct Span {
    double lo_u, hi_u, lo_v, hi_v;            // the (normalised) parameters it takes
    double start_u, half_u, start_v, half_v;  // its centre and half length
    size_t offset;                            // of its coefficients in coeffs_
  };

  // The span holding (nu, nv), its coefficients built on first use (BSplSLib_Cache::BuildCache
  // for the span that OCCT locates for the span's middle).
  const Span& Find(const Geom_BSplineSurface& s, const std::vector<double>& uknots,
                   const std::vector<double>& vknots, double nu, double nv) {
    Span span;
    const int iu = KnotSpan(uknots, nu, &span.lo_u, &span.hi_u);
    const int iv = KnotSpan(vknots, nv, &span.lo_v, &span.hi_v);
    const uint64_t key = static_cast<uint64_t>(iu) << 32 | static_cast<uint32_t>(iv);
    auto found = index_.find(key);
    if (found != index_.end()) return spans_[found->second];
    if (spans_.size() >= kMaxSpans) {  // a bound on memory; a span's coefficients never change
      spans_.clear(), index_.clear(), coeffs_.clear();
    }
    index_.emplace(key, spans_.size());
    double mu = 0.5 * (uknots[iu - 1] + uknots[iu]);
    double mv = 0.5 * (vknots[iv - 1] + vknots[iv]);
    u_.LocateParameter(mu, s.UKnotSequence());
    v_.LocateParameter(mv, s.VKnotSequence());
    const double half_u = 0.5 * u_.SpanLength, half_v = 0.5 * v_.SpanLength;
    span.start_u = u_.SpanStart + half_u, span.half_u = half_u;
    span.start_v = v_.SpanStart + half_v, span.half_v = half_v;
    span.offset = coeffs_.size();
    const int rows = std::max(u_.Degree, v_.Degree) + 1;
    TColStd_Array2OfReal coeffs(1, rows, 1, static_cast<int>(size_) / rows);
    BSplSLib::BuildCache(span.start_u, span.start_v, half_u, half_v, u_.IsPeriodic, v_.IsPeriodic,
                         u_.Degree, v_.Degree, u_.SpanIndex, v_.SpanIndex, s.UKnotSequence(),
                         s.VKnotSequence(), s.Poles(), s.Weights(), coeffs);
    coeffs_.insert(coeffs_.end(), &coeffs(1, 1), &coeffs(1, 1) + size_);
    spans_.push_back(span);
    last_ = previous_ = nullptr;  // spans_ may have moved
    return spans_.back();
  }

  // The span's polynomial at (t_major, t_minor) into r[0..dimension): Horner's rule along the
  // direction of higher degree `major` for each of the coefficient rows' columns, then along the
  // other (PLib::NoDerivativeEvalPolynomial twice). kDim and kMinor > 0 fix the row length, so
  // that the compiler unrolls the columns; the arithmetic per column is the same.
  template <int kDim, int kMinor>
  static void Horner(const double* coeffs, int major, int minor, int dimension, double t_major,
                     double t_minor, double r[4]) {
    if constexpr (kMinor > 0) {
      // Per minor index i, the first two coordinates as one pair and the rest one by one, in
      // fixed-size arrays indexed by constants once the loops unroll, so that they stay in
      // registers: the same operations on each element as the general loop below (a row walked
      // by pointer went through the stack, read back at other offsets than it was written).
      typedef double Pair __attribute__((vector_size(16)));
      constexpr int kCols = kDim * (kMinor + 1), kRest = kDim - 2;
      Pair pair[kMinor + 1];
      double rest[kMinor + 1][kRest > 0 ? kRest : 1];
      const double* c = coeffs + major * kCols;
      auto load = [&](const double* at, int i) {
        Pair p;
        std::memcpy(&p, at + i * kDim, sizeof(p));
        return p;
      };
      for (int i = 0; i <= kMinor; ++i) {
        pair[i] = load(c, i);
        for (int k = 0; k < kRest; ++k) rest[i][k] = c[i * kDim + 2 + k];
      }
      const Pair tm = {t_major, t_major};
      for (int step = 0; step < major; ++step) {
        c -= kCols;
        for (int i = 0; i <= kMinor; ++i) {
          pair[i] = pair[i] * tm + load(c, i);
          for (int k = 0; k < kRest; ++k) rest[i][k] = rest[i][k] * t_major + c[i * kDim + 2 + k];
        }
      }
      const Pair tn = {t_minor, t_minor};
      Pair out = pair[kMinor];
      double out_rest[kRest > 0 ? kRest : 1];
      for (int k = 0; k < kRest; ++k) out_rest[k] = rest[kMinor][k];
      for (int i = kMinor - 1; i >= 0; --i) {
        out = out * tn + pair[i];
        for (int k = 0; k < kRest; ++k) out_rest[k] = out_rest[k] * t_minor + rest[i][k];
      }
      r[0] = out[0], r[1] = out[1];
      for (int k = 0; k < kRest; ++k) r[2 + k] = out_rest[k];
    } else {
      const int cols = dimension * (minor + 1);
      double row[4 * 26];  // cols <= 4 x (BSplCLib::MaxDegree() + 1)
      const double* c = coeffs + major * cols;
      for (int j = 0; j < cols; ++j) row[j] = c[j];
      for (int i = 0; i < major; ++i) {
        c -= cols;
        for (int j = 0; j < cols; ++j) row[j] = row[j] * t_major + c[j];
      }
      const double* d = row + minor * dimension;
      for (int j = 0; j < dimension; ++j) r[j] = d[j];
      for (int i = 0; i < minor; ++i) {
        d -= dimension;
        for (int j = 0; j < dimension; ++j) r[j] = r[j] * t_minor + d[j];
      }
    }
  }

  static constexpr size_t kMaxSpans = size_t{1} << 15;
  BSplCLib_CacheParams u_, v_;  // the span last located (Find), and the normalisation
  const int dimension_;         // 3, or 4 with the weight
  const size_t size_;           // coefficients per span
  void (*horner_)(const double*, int, int, int, double, double, double*) = Horner<0, 0>;
  std::vector<Span> spans_;
  std::unordered_map<uint64_t, size_t> index_;  // (u span, v span) -> spans_ index
  std::vector<double> coeffs_;
  const Span* last_ = nullptr;
  const Span* previous_ = nullptr;  // the one last_ held before
};

}  // namespace rdmesh
