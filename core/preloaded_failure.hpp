#pragma once
/// \file
/// Failure under a preload (cure stresses: issue 33). A member's state is a fixed part, the preload
/// (the cured specimen before the test's load: the bonds' free offsets and where they put it), plus
/// a load factor lambda times a unit part. Its utilisation u(lambda) (1 at failure) is then no
/// longer lambda u(1), and its critical load factor is the root of u(lambda) = 1 rather than
/// 1 / u(1). The events solver finds it so for its bonds and its sites
/// (solvers/bond_events.hpp); for a convex failure surface (every criterion of
/// core/failure_criteria.hpp, the bonds' laws) u is convex along lambda, and with u(0) < 1 the
/// first crossing is the only one.

#include <functional>

namespace plydem {

/// The smallest load factor lambda >= 0 at which `utilisation(lambda)` reaches 1: 0 when it does at
/// lambda = 0 (the preload alone fails the member), +infinity when it does not up to 2^60 times
/// the scale (`guess`, the proportional estimate 1 / u(1) where finite and positive, else 1).
/// Brackets the crossing from `guess` (doubling), then narrows it by regula falsi (Illinois) with
/// bisection where that stalls, to a relative 1e-14; returns the bracket's failing end, at which
/// the utilisation is at least 1. With no preload (u(lambda) = lambda u(1)) that is `guess` to
/// within round-off.
double first_failure_factor(const std::function<double(double)>& utilisation, double guess);

/// The smallest lambda >= 0 at which a + b lambda + c lambda^2 reaches `target` (a quadratic
/// energy growing from a < target), +infinity if never; c >= 0.
double first_quadratic_crossing(double a, double b, double c, double target);

}  // namespace plydem
