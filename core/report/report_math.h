#pragma once
// The report's two derived figures: "worth N x samples" and the Pareto fronts.
#include <utility>
#include <vector>

namespace mcr {

// The sample count at which the noisy render would reach `relmse`, over `input_spp`. `levels`
// are (spp, relMSE) of the scene's noisy renders in increasing spp; between two levels
// relMSE is a power of spp (log-log linear), beyond them the nearest two are extended; with
// one level relMSE ~ 1/spp (an unbiased estimator's variance). -1 when it cannot be said
// (no level, levels that do not fall with spp, relmse not positive).
double worth_x_samples(const std::vector<std::pair<int, double>>& levels, int input_spp, double relmse);

// For points (seconds, error): true where no other point is at least as fast and at least as
// good, and better in one (lower error when lower_is_better, else higher).
std::vector<bool> pareto_front(const std::vector<std::pair<double, double>>& points, bool lower_is_better);

}  // namespace mcr
