#include "jointlab/correlate/two_chain.h"

#include <vector>

namespace jointlab::correlate {

model::Model two_chain_structure(const TwoChainParameters& p) {
  const int n = p.n < 6 ? 6 : p.n;
  const int size = 2 * n;
  std::vector<Eigen::Triplet<double>> k, m;
  auto spring = [&](int a, int b, double v) {
    k.emplace_back(a, a, v);
    if (b >= 0) {
      k.emplace_back(b, b, v);
      k.emplace_back(a, b, -v);
      k.emplace_back(b, a, -v);
    }
  };
  model::Model out;
  auto joint = [&](int a, int b, const std::string& element, double v) {
    model::Joint j;
    j.a = a;
    j.b = b;
    j.element = element;
    j.stiffness = v;
    if (element.starts_with("iwan.")) j.iwan = model::Iwan(p.Fs, v, p.chi, p.beta);
    out.joints.push_back(j);
  };
  for (int c = 0; c < 2; ++c) {
    const int o = c * n;
    for (int i = 0; i < n; ++i) m.emplace_back(o + i, o + i, c == 0 ? 0.5 : 0.3);
    spring(o, -1, 2e6);
    for (int i = 0; i + 1 < n; ++i) {
      const int a = o + i, b = o + i + 1;
      if (c == 0 && i == 1) {
        spring(a, b, 2e5);
        joint(a, b, p.iwan ? "iwan.rivet" : "spring.ka", p.ka);
      } else if (c == 0 && i == 3) {
        joint(a, b, "spring.kflat", p.kflat);
      } else if (c == 1 && i == 1) {
        joint(a, b, "spring.kb", p.kb);
      } else {
        spring(a, b, 1e6);
      }
    }
  }
  out.mass.resize(size, size);
  out.mass.setFromTriplets(m.begin(), m.end());
  out.stiffness.resize(size, size);
  out.stiffness.setFromTriplets(k.begin(), k.end());
  model::validate_model(out, "two-chain structure");
  return out;
}

}  // namespace jointlab::correlate
