#pragma once
// The work of the grips along an events path, from the path alone.
#include "solvers/bond_events.hpp"

namespace plydem::test {

// The grips' work along the events path: critical states joined by the secant lines of the
// stiffness between them, the drops at fixed grips doing no work. On the secant of event k + 1 the
// reaction is R_{k+1} / lambda_{k+1} per unit load factor, so the work from lambda_k to
// lambda_{k+1} is 1/2 (R_{k+1} / lambda_{k+1}) (lambda_{k+1}^2 - lambda_k^2) times the grip
// travel per unit load factor `travel`; the first secant starts at zero.
inline double area_under_path(const EventsResult& r, double travel) {
  double work = 0, previous = 0;
  for (const EventPoint& p : r.path) {
    const double secant = p.reaction / p.load_factor;
    work += 0.5 * secant * (p.load_factor * p.load_factor - previous * previous) * travel;
    previous = p.load_factor;
  }
  return work;
}

}  // namespace plydem::test
