#pragma once
// Shirley et al. 2011, "A local image reconstruction algorithm for stochastic rendering":
// the per-pixel reconstructions from the samples around one pixel. Alg 1 (box), Alg 1B
// (variable-width splat), Alg 2 generalised to K box scales (Appendix B) with the blend
// between neighbouring scales of Appendix A, the w^p "less blur" variant (fig. 5), and the
// layered depth-of-field path that needs no sort (section 3.1, last paragraph).
//
// Weights follow Appendix A: a sample's box weight at scale s is q / s^2 inside the s x s
// square around the pixel centre, q = coverage / samples in the sample's own pixel, so the
// weights of one scale over a fully covered square sum to 1 (what makes "coverage" mean
// coverage). One deliberate change: the free share 1 - (coverage of the other scales) is
// clamped at 0. With the same sample count in every pixel it never goes below 0; with
// counts that differ between pixels it can, and a negative weight would let c/w leave the
// samples' range.
#include <algorithm>
#include <vector>

namespace mcr::sweep {

// Box widths in pixels, ascending.
struct Scales {
  std::vector<float> widths;
  // count widths evenly spaced from 1 to widest: (2, 5) = {1, 5} (Appendix A),
  // (4, 7) = {1, 3, 5, 7} (Appendix B); count 1 = {widest}.
  static Scales even(int count, float widest);
  int size() const { return int(widths.size()); }
  float widest() const { return widths.back(); }
};

// One sample as a pixel sees it.
struct Sample {
  float dx = 0, dy = 0;  // position minus the pixel centre, pixels
  float z = 0;           // depth (front to back = ascending); +inf for the background
  float d = 1;           // denoising diameter, pixels
  float q = 1;           // weight scale: coverage / samples in the sample's pixel
  float rgb[3] = {0, 0, 0};
};

// The scales a diameter is filtered at: (1 - t) at scale k, t at scale k + 1.
struct Assign {
  int k = 0;
  float t = 0;
  bool operator==(const Assign& o) const { return k == o.k && t == o.t; }
};
// Without blending (Alg 2, Appendix B): the widest scale k with d > widths[k], else the
// narrowest. With blending (Appendix A generalised): d between widths[k] and widths[k+1]
// goes to both, linearly (Appendix A's two-scale ramp, clamp((D - 1) / 5), ends at D = 6;
// this one ends at the wide scale's width, D = 5, and stays continuous for any K).
Assign assign(float d, const Scales& s, bool blend);

struct Options {
  Scales scales = Scales::even(2, 5);
  bool blend = true;
  float power = 1;  // each sample's weight w_i becomes w_i^power (fig. 5: 1.3 blurs less)
};

// Results are c / w over the samples that got weight; false (and 0) when none did.

// Alg 1 (variable = false: the 1-pixel box) and Alg 1B (variable = true: a box of width d
// clamped to [1, widest], weight 1/d^2).
bool splat(const Sample* s, int n, bool variable, float widest, float out[3]);

// Alg 2 over K scales: sorts s front to back (ties by position in the array) and sweeps.
// Where every sample has the same single scale the sweep is a box of that scale, whatever
// the order: no sort (*sorted says which happened).
bool sweep(Sample* s, int n, const Options& o, float out[3], bool* sorted = nullptr);

// The same result as sweep() with no sort, when each sample's diameter is a circle of
// confusion: a function of depth that falls towards `focus` and rises beyond it, so the
// samples of one scale on one side of the focus are contiguous in depth (a layer) and the
// order inside a layer does not change the result. Requires o.blend = false.
bool layered(const Sample* s, int n, const Options& o, float focus, float out[3]);

// The layered path in two steps, for callers that sum whole pixels at once (the filter, when
// the widths are odd integers: a box then holds whole pixels). Layer of a sample: 0 .. 2K-2,
// front to back (near side widest first, in focus, far side).
int layer_of(float z, float d, const Options& o, float focus);
// Per layer and per narrowest box m holding the sample: sums of q, q^power and q^power * rgb.
struct LayerSums {
  struct Acc {
    double q = 0, qp = 0, c[3] = {0, 0, 0};
  };
  int K, L;
  std::vector<Acc> acc;
  explicit LayerSums(int k) : K(k), L(2 * k - 1), acc(std::size_t(L * K)) {}
  void clear() { std::fill(acc.begin(), acc.end(), Acc{}); }
  void add(const Sample& s, int layer, int m, double power);
  // Adds another's sums with every narrowest box raised to at least m_at_least.
  void add(const LayerSums& other, int m_at_least);
};
bool combine_layers(const LayerSums& sums, const Options& o, float out[3]);

}  // namespace mcr::sweep
