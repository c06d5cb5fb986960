#include "solvers/bond_events.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "contacts/bond_kernel.hpp"
#include "contacts/bond_opening.hpp"
#include "core/disjoint_sets.hpp"
#include "core/error.hpp"
#include "core/preloaded_failure.hpp"
#include "core/stopwatch.hpp"
#include "solvers/linear_solver.hpp"

namespace plydem {

void EventSettings::validate() const {
  require(max_events > 0, fmt::format("events: max_events is {}, must be positive", max_events));
  require(stop_fraction >= 0 && stop_fraction < 1,
          fmt::format("events: stop_fraction is {}, must lie in [0, 1)", stop_fraction));
  require(tooth_stiffness_ratio > 0 && tooth_stiffness_ratio < 1,
          fmt::format("events: tooth_stiffness_ratio is {}, must lie in (0, 1)",
                      tooth_stiffness_ratio));
  require(last_tooth_stiffness > 0 && last_tooth_stiffness <= tooth_stiffness_ratio,
          fmt::format("events: last_tooth_stiffness is {}, must lie in (0, tooth_stiffness_ratio "
                      "= {}] (a softening bond has at least one tooth)",
                      last_tooth_stiffness, tooth_stiffness_ratio));
  require(max_update_rank >= 0,
          fmt::format("events: max_update_rank is {}, must be >= 0", max_update_rank));
  require(checkpoint_every >= 0,
          fmt::format("events: checkpoint_every is {}, must be >= 0", checkpoint_every));
  require(progress_seconds > 0,
          fmt::format("events: progress_seconds is {}, must be positive", progress_seconds));
  plydem::validate(static_settings);
  if (material_point) {
    require(!material_point->ply_angles.empty(),
            "events: failure at the material point needs the fibre angle of every ply");
    for (double angle : material_point->ply_angles)
      require(std::isfinite(angle), fmt::format("events: a ply angle is {}", angle));
  }
  require(static_settings.method != StaticMethod::kIterative,
          "events: the events solver updates a factor of the stiffness, so it needs the direct "
          "method (StaticMethod::kDirect or kAuto), not the conjugate gradient");
}

namespace {

using Clock = Stopwatch::Clock;

// The smallest pivot of the capacitance matrix, relative to its column of W^-1, that the updates
// accept (see UnitLoadSolver::change).
constexpr double kPivotFloor = 1e-8;

Eigen::Vector3d segment(const Eigen::VectorXd& u, int particle, int offset) {
  return u.segment<3>(kDofsPerParticle * particle + offset);
}

// The 12 dofs of bond b in the order of parallel_bond_stiffness: (u_i, theta_i, u_j, theta_j).
std::array<int, 12> bond_dofs(const Bonds& bonds, int b) {
  std::array<int, 12> dofs{};
  for (int c = 0; c < kDofsPerParticle; ++c) {
    dofs[c] = kDofsPerParticle * bonds.first(b) + c;
    dofs[kDofsPerParticle + c] = kDofsPerParticle * bonds.second(b) + c;
  }
  return dofs;
}

// A bond's changeable fields in EventChange's order: k_n, k_s, k_b, k_t, damage, state.
void read_bond_fields(const Bonds& bonds, int b, double* v) {
  v[0] = bonds.normal_stiffness(b);
  v[1] = bonds.shear_stiffness(b);
  v[2] = bonds.bending_stiffness(b);
  v[3] = bonds.twisting_stiffness(b);
  v[4] = bonds.damage(b);
  v[5] = bonds.state(b);
}

void write_bond_fields(Bonds& bonds, int b, const double* v) {
  bonds.normal_stiffness(b) = v[0];
  bonds.shear_stiffness(b) = v[1];
  bonds.bending_stiffness(b) = v[2];
  bonds.twisting_stiffness(b) = v[3];
  bonds.damage(b) = v[4];
  bonds.state(b) = static_cast<int>(v[5]);
}

Matrix12d symmetric_bond_stiffness(const BondParameters& params) {
  const Matrix12d k = parallel_bond_stiffness(params);
  return 0.5 * (k + k.transpose());  // as the assembly does (solvers/stiffness_assembly.hpp)
}

// Clusters of particles joined by intact bonds: a label per particle (0 .. count - 1).
int intact_clusters(const Model& model, std::vector<int>& label) {
  const int n = model.particles.size();
  DisjointSets sets(n);
  for (int b = 0; b < model.bonds.size(); ++b)
    if (!model.bonds.is_broken(b)) sets.join(model.bonds.first(b), model.bonds.second(b));
  label.assign(n, -1);
  int count = 0;
  for (int i = 0; i < n; ++i) {
    const int root = sets.find(i);
    if (label[root] < 0) label[root] = count++;
    label[i] = label[root];
  }
  return count;
}

void check_inputs(const Model& model, const DofConstraints& unit, const DofFlags& reaction_dofs,
                  bool material_point) {
  model.check_consistency();  // sizes, stiffnesses, and the strength fields of every bond
  const Bonds& bonds = model.bonds;
  require(material_point || bonds.breakable(),
          "events: every bond of the model is unbreakable (infinite tensile strength and "
          "cohesion) and no failure at the material point is set: assign strengths before "
          "running to failure");
  const int n = model.particles.size();
  require(unit.fixed.rows() == n && unit.value.rows() == n,
          fmt::format("events: the prescribed dofs are for {} particles, the model has {}",
                      unit.fixed.rows(), n));
  require(reaction_dofs.rows() == n,
          fmt::format("events: the reaction dofs are for {} particles, the model has {}",
                      reaction_dofs.rows(), n));
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < kDofsPerParticle; ++c)
      if (reaction_dofs(i, c) && !unit.fixed(i, c))
        throw Error(
            fmt::format("events: the reaction is summed over {} of particle {}, which is "
                        "not prescribed (only prescribed dofs carry a reaction)",
                        dof_name(static_cast<Dof>(c)), i));
  require(reaction_dofs.any(), "events: no reaction dof is flagged");
  for (int b = 0; b < bonds.size(); ++b) {
    const bool zero_stiffness = bonds.normal_stiffness(b) == 0 && bonds.shear_stiffness(b) == 0 &&
                                bonds.bending_stiffness(b) == 0 && bonds.twisting_stiffness(b) == 0;
    if (bonds.is_broken(b) && !(zero_stiffness && bonds.damage(b) == 1))
      throw Error(
          fmt::format("events: bond {} is broken but has damage {} and a non-zero "
                      "stiffness (a broken bond has damage 1 and zero stiffness)",
                      b, bonds.damage(b)));
    if (!bonds.is_broken(b) && !(bonds.damage(b) < 1))
      throw Error(fmt::format("events: bond {} has damage 1 but its state is intact", b));
  }
}

/// The equilibrium at unit load with the current stiffness: a factor of the stiffness at the last
/// factorization (StaticSystem), corrected for the bonds changed since by Woodbury's identity.
///
/// With K0 the factored free-free stiffness and each change of a bond a removed stiffness
/// Delta K >= 0 (k_old - k_new in every component), the current one is K = K0 - V W V^T: for each
/// change, the bond's Delta K restricted to its free dofs, M = D^-1 Q Lambda Q^T D^-1, from the
/// eigen-decomposition of its Jacobi-scaled form D M D (D = diag(M)^-1/2, so that translations
/// and rotations are equally resolved), gives the columns V = D^-1 Q and weights W = Lambda of its
/// non-zero eigenvalues (rank 6 at most for a bond with both ends free). Then
///   K^-1 = K0^-1 + Z C^-1 Z^T,   Z = K0^-1 V,   C = W^-1 - V^T Z,
/// C positive definite as long as K is. The changed bonds also change the right-hand side -K_fp g
/// by V a (the part of Delta K coupling their free dofs to prescribed ones lies in the range of
/// V), so the solution is
///   u_f = u0 + Z (a + C^-1 (V^T u0 + G a)),   G = V^T Z,   u0 = K0^-1 b0.
/// Z, G and the Cholesky factor of C grow by the columns of each change (a bordered Cholesky),
/// so a change costs its few solves with K0's factor and O(rank^2), an equilibrium O(dofs rank).
/// The bonds of one site's crack change together: their columns share one solve with the factor
/// (one pass over it instead of one per bond; bench/README.md, "Events per crack, not per bond
/// (`bench/strength_events`)").
///
/// Only the dofs the load reaches matter: the stiffness graph of a layer in the x-y plane falls
/// apart into in-plane and out-of-plane dofs, and the solution is exactly zero on the part that no
/// prescribed non-zero value touches. Those "active" dofs are found once per set of constraints;
/// the columns of a change are kept on them alone (half the rank for a hex2d layer pulled in its
/// plane), and exactly so: Delta K never couples active to inactive dofs.
///
/// A preload (bond_events.hpp, "Preload") is a second right-hand side on the same factor and
/// updates: the prescribed values at load factor 0 and the bonds' free offsets q, whose load on a
/// changed bond falls with its stiffness, by Delta K q^ (q^ the offset as a translation of the
/// bond's second particle), which lies in the range of V as Delta K_fp does. Both columns share Z,
/// G and C; each has its own u0, a and V^T u0.
class UnitLoadSolver {
 public:
  UnitLoadSolver(const EventSettings& settings, const DofConstraints& unit, const DofArray& preload,
                 bool preloaded)
      : settings_(settings.static_settings),
        constraints_(unit),
        preload_(preload),
        preloaded_(preloaded),
        refactor_every_change_(settings.refactor_every_event || settings.max_update_rank == 0),
        max_rank_(settings.max_update_rank) {
    if (settings_.method == StaticMethod::kAuto) settings_.method = StaticMethod::kDirect;
    settings_.linear_solver_use = LinearSolverUse::kManySolves;  // a factor to update
  }

  /// The constraints with the pins and the fixed loose pieces.
  const DofConstraints& constraints() const { return constraints_; }
  int factorizations() const { return factorizations_; }
  int rank() const { return rank_; }

  /// The preload's prescribed values (the loose pieces' included).
  const DofArray& preload() const { return preload_; }

  /// A new set of prescribed dofs (more of them) and their values at load factor 0: the stiffness
  /// is factored at the next solve.
  void set_constraints(const DofConstraints& constraints, const DofArray& preload) {
    constraints_ = constraints;
    preload_ = preload;
    stale_ = true;
    active_stale_ = true;
  }

  /// The unit-load solution (every dof, 6 * particle + component) for the model's current bonds,
  /// and with a preload the preload's state into `preloaded` (left alone without one). May factor
  /// the stiffness (then it writes the factored system's solution into the model's particles, as
  /// StaticSystem::solve does) and throws plydem::Error as StaticSystem does.
  void solve(Model& model, Eigen::VectorXd& u, Eigen::VectorXd& preloaded) {
    if (stale_) factor(model);
    u = u0_.col(0);
    if (preloaded_) preloaded = u0_.col(1);
    if (rank_ == 0) return;
    const int r = rank_;
    const Eigen::MatrixXd h = y0_.topRows(r) + g_.topLeftCorner(r, r) * a_.topRows(r);
    Eigen::MatrixXd x = l_.topLeftCorner(r, r).triangularView<Eigen::Lower>().solve(h);
    l_.topLeftCorner(r, r).triangularView<Eigen::Lower>().transpose().solveInPlace(x);
    const Eigen::MatrixXd du = z_.leftCols(r) * (a_.topRows(r) + x);
    for (std::size_t k = 0; k < active_dofs_.size(); ++k) u(active_dofs_[k]) += du(k, 0);
    if (!preloaded_) return;
    for (std::size_t k = 0; k < active_dofs_.size(); ++k) preloaded(active_dofs_[k]) += du(k, 1);
  }

  /// Bond b's stiffness lost `removed` (its BondParameters with the stiffness taken away);
  /// model.bonds holds the new stiffness already.
  void change(const Model& model, int b, const BondParameters& removed, const EventChange& record) {
    change_together(model, {{b, removed}}, {record});
  }

  /// Several bonds' changes in one update (a site's crack): their columns share one solve with
  /// the factor, where a change at a time solves for each bond's few columns apart (a pass over
  /// the factor each). records[k] is bond k's, its joins_previous set for all but the first.
  void change_together(const Model& model,
                       const std::vector<std::pair<int, BondParameters>>& removed,
                       const std::vector<EventChange>& records) {
    if (stale_) return;
    history_.insert(history_.end(), records.begin(), records.end());
    change_terms(model, removed);
    if (stale_) history_.clear();  // the next solve factors the current stiffness
  }

  bool stale() const { return stale_; }

  /// The solver's part of a checkpoint.
  void save(EventsState& s) const {
    s.constraints = constraints_;
    s.factored_from = factored_from_;
    s.preload = preload_;
    s.preload_factored_from = preload_factored_from_;
    s.stale = stale_;
    s.active_stale = active_stale_;
    s.active_dofs = active_stale_ ? std::vector<int>{} : active_dofs_;
    s.capacity = stale_ ? static_cast<long>(z_.cols()) : capacity_at_factor_;
    s.changes = stale_ ? std::vector<EventChange>{} : history_;
    s.result.factorizations = factorizations_;
  }

  /// A fresh solver continues a saved one: the model's bonds are the saved run's at its
  /// checkpoint. Undoes the changes since the last factorization, factors as it did, and applies
  /// the changes again (what the saved solver did, in the same order: the same factor and terms).
  void restore(Model& model, const EventsState& s) {
    const int dofs = kDofsPerParticle * model.particles.size();
    active_stale_ = s.active_stale;
    if (!active_stale_) {
      active_dofs_ = s.active_dofs;
      active_of_dof_.assign(dofs, -1);
      for (std::size_t k = 0; k < active_dofs_.size(); ++k) {
        const int dof = active_dofs_[k];
        require(dof >= 0 && dof < dofs, "checkpoint: an active dof is out of range");
        active_of_dof_[dof] = static_cast<int>(k);
      }
    }
    stale_ = true;
    if (s.stale) {
      constraints_ = s.constraints;
      preload_ = s.preload;
      allocate(s.capacity);
      factorizations_ = s.result.factorizations;
      return;
    }
    Bonds& bonds = model.bonds;
    for (const EventChange& c : s.changes)
      require(c.bond >= 0 && c.bond < bonds.size(), "checkpoint: a change names no bond");
    for (auto c = s.changes.rbegin(); c != s.changes.rend(); ++c)
      write_bond_fields(bonds, c->bond, c->before);
    constraints_ = s.factored_from;
    preload_ = s.preload_factored_from;
    factor(model);
    allocate(s.capacity);
    capacity_at_factor_ = s.capacity;
    // The changes again, each group of them (a site's crack) in one update, as they were made.
    std::vector<std::pair<int, BondParameters>> group;
    std::vector<EventChange> records;
    auto apply_group = [&] {
      if (!group.empty()) change_together(model, group, records);
      group.clear();
      records.clear();
    };
    for (const EventChange& c : s.changes) {
      if (!c.joins_previous) apply_group();
      BondParameters removed = bond_parameters(bonds, c.bond);
      removed.normal_stiffness = c.removed[0];
      removed.shear_stiffness = c.removed[1];
      removed.bending_stiffness = c.removed[2];
      removed.twisting_stiffness = c.removed[3];
      write_bond_fields(bonds, c.bond, c.after);
      group.emplace_back(c.bond, removed);
      records.push_back(c);
    }
    apply_group();
    factorizations_ = s.result.factorizations;
  }

 private:
  // The update's arrays at `capacity` columns (what reserve() leaves after growing to it).
  void allocate(long capacity) {
    if (capacity <= 0 || active_stale_) return;
    const auto c = static_cast<Eigen::Index>(capacity);
    z_ = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(active_dofs_.size()), c);
    g_ = Eigen::MatrixXd::Zero(c, c);
    l_ = Eigen::MatrixXd::Zero(c, c);
    a_ = Eigen::MatrixXd::Zero(c, right_hand_sides());
    y0_ = Eigen::MatrixXd::Zero(c, right_hand_sides());
  }

  void change_terms(const Model& model,
                    const std::vector<std::pair<int, BondParameters>>& removed) {
    if (refactor_every_change_) {
      stale_ = true;
      return;
    }
    std::vector<ChangeColumns> changes;
    Eigen::Index columns = 0;
    for (const auto& [b, r] : removed) {
      ChangeColumns change;
      if (!change_columns(model, b, r, change)) continue;
      columns += change.v.cols();
      changes.push_back(std::move(change));
    }
    if (changes.empty()) return;
    if (rank_ + columns > max_rank_) {
      stale_ = true;
      return;
    }
    const Eigen::MatrixXd z = solve_columns(changes, columns);
    Eigen::Index first = 0;
    for (const ChangeColumns& change : changes) {
      if (!append_columns(change, z.middleCols(first, change.v.cols()))) {
        stale_ = true;
        return;
      }
      first += change.v.cols();
    }
  }

  // One change's part of V, W and the right-hand side (see the class comment), on its active dofs.
  struct ChangeColumns {
    std::array<int, 12> dofs{};   // the bond's dofs (bond_dofs)
    std::array<int, 12> local{};  // the bond's active dofs, as rows 0..na-1 of its stiffness
    int na = 0;
    Eigen::MatrixXd v;      // na x q: the columns of V
    Eigen::VectorXd w;      // q: the weights W
    Eigen::MatrixXd a, y0;  // q x right_hand_sides(): a and V^T u0 of each right-hand side
  };

  // The columns of bond b's change `removed`; false if there are none (the load does not reach
  // the bond's dofs, or nothing is removed).
  bool change_columns(const Model& model, int b, const BondParameters& removed,
                      ChangeColumns& out) const {
    out.dofs = bond_dofs(model.bonds, b);
    const std::array<int, 12>& dofs = out.dofs;
    std::array<int, 12>& local = out.local;
    const Matrix12d k = symmetric_bond_stiffness(removed);
    int na = 0;
    for (int r = 0; r < 12; ++r)
      if (active_of_dof_[dofs[r]] >= 0) local[na++] = r;
    out.na = na;
    if (na == 0) return false;  // the load does not reach this bond's dofs

    // Delta K on the active dofs, its right-hand side part (Delta K)_fp g (and for the preload
    // (Delta K)_fp g_0 - (Delta K q^)_f), and the scaling D.
    Eigen::MatrixXd m(na, na);
    Eigen::MatrixXd db = Eigen::MatrixXd::Zero(na, right_hand_sides());
    Eigen::VectorXd d(na);
    const Eigen::Vector3d offset =
        preloaded_ ? Eigen::Vector3d(model.bonds.free_offset.row(b).transpose().matrix())
                   : Eigen::Vector3d::Zero();
    for (int r = 0; r < na; ++r) {
      for (int c = 0; c < na; ++c) m(r, c) = k(local[r], local[c]);
      for (int c = 0; c < 12; ++c) {
        const int particle = dofs[c] / kDofsPerParticle, component = dofs[c] % kDofsPerParticle;
        if (!constraints_.fixed(particle, component)) continue;
        db(r, 0) += k(local[r], c) * constraints_.value(particle, component);
        if (preloaded_) db(r, 1) += k(local[r], c) * preload_(particle, component);
      }
      if (preloaded_)
        for (int c = 0; c < 3; ++c) db(r, 1) -= k(local[r], 6 + c) * offset(c);
      d(r) = m(r, r) > 0 ? 1 / std::sqrt(m(r, r)) : 1.0;
    }
    const Eigen::MatrixXd scaled = d.asDiagonal() * m * d.asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
    const double largest = eigen.eigenvalues().maxCoeff();
    if (!(largest > 0)) return false;
    std::vector<int> kept;
    for (int e = 0; e < na; ++e)
      if (eigen.eigenvalues()(e) > 1e-12 * largest) kept.push_back(e);
    const int q = static_cast<int>(kept.size());
    Eigen::MatrixXd qk(na, q);
    out.w.resize(q);
    for (int e = 0; e < q; ++e) {
      qk.col(e) = eigen.eigenvectors().col(kept[e]);
      out.w(e) = eigen.eigenvalues()(kept[e]);
    }
    out.v = d.cwiseInverse().asDiagonal() * qk;
    out.a = qk.transpose() * d.asDiagonal() * db;
    Eigen::MatrixXd u0_local(na, right_hand_sides());
    for (int r = 0; r < na; ++r) u0_local.row(r) = u0_.row(dofs[local[r]]);
    out.y0 = out.v.transpose() * u0_local;
    return true;
  }

  // Z = K0^-1 V for the changes' columns (`columns` of them, change after change), on the active
  // dofs: one solve.
  Eigen::MatrixXd solve_columns(const std::vector<ChangeColumns>& changes,
                                Eigen::Index columns) const {
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(free_count_, columns);
    Eigen::Index first = 0;
    for (const ChangeColumns& change : changes) {
      for (int r = 0; r < change.na; ++r) {
        rhs.row(free_of_dof_[change.dofs[change.local[r]]]).segment(first, change.v.cols()) =
            change.v.row(r);
      }
      first += change.v.cols();
    }
    system_->solve_free_in_place(rhs);
    Eigen::MatrixXd z(active_dofs_.size(), columns);
    for (std::size_t k2 = 0; k2 < active_dofs_.size(); ++k2)
      z.row(k2) = rhs.row(free_of_active_[k2]);
    return z;
  }

  // Appends one change's columns (Z = K0^-1 V) to Z, G, a, V^T u0 and the Cholesky factor of C;
  // false, leaving them as they were, where the factor would be inaccurate.
  bool append_columns(const ChangeColumns& change, const Eigen::Ref<const Eigen::MatrixXd>& z) {
    const int q = static_cast<int>(change.v.cols());
    const Eigen::MatrixXd& v = change.v;
    // G's new columns: V_s^T Z over every earlier change s, and this change's own block.
    const int r0 = rank_;
    Eigen::MatrixXd g_cross(r0, q);
    for (const Term& t : terms_) {
      Eigen::MatrixXd z_rows(t.rows.size(), q);
      for (std::size_t k2 = 0; k2 < t.rows.size(); ++k2) z_rows.row(k2) = z.row(t.rows[k2]);
      g_cross.middleRows(t.column, t.v.cols()) = t.v.transpose() * z_rows;
    }
    Term term;
    term.column = r0;
    term.v = v;
    term.rows.resize(change.na);
    Eigen::MatrixXd z_own(change.na, q);
    for (int r = 0; r < change.na; ++r) {
      term.rows[r] = active_of_dof_[change.dofs[change.local[r]]];
      z_own.row(r) = z.row(term.rows[r]);
    }
    Eigen::MatrixXd g_own = v.transpose() * z_own;
    g_own = 0.5 * (g_own + g_own.transpose()).eval();

    // Bordered Cholesky of C = W^-1 - G: L21 = C21 L11^-T, L22 L22^T = C22 - L21 L21^T.
    Eigen::MatrixXd x = -g_cross;
    if (r0 > 0) l_.topLeftCorner(r0, r0).triangularView<Eigen::Lower>().solveInPlace(x);
    Eigen::MatrixXd c22 = -g_own;
    c22.diagonal() += change.w.cwiseInverse();
    const Eigen::MatrixXd schur = c22 - x.transpose() * x;
    const Eigen::LLT<Eigen::MatrixXd> llt(schur);
    // C <= W^-1, and a pivot far below its column's W^-1 is lost to cancellation: the current
    // stiffness nearly loses that direction (a near-mechanism), and the updated factor would be
    // inaccurate there. Factor the current stiffness instead.
    const Eigen::MatrixXd l22 = llt.matrixL();
    bool accurate = llt.info() == Eigen::Success;
    for (int e = 0; accurate && e < q; ++e)
      accurate = l22(e, e) * l22(e, e) * change.w(e) > kPivotFloor;
    if (!accurate) return false;

    reserve(r0 + q);
    z_.middleCols(r0, q) = z;
    g_.block(0, r0, r0, q) = g_cross;
    g_.block(r0, 0, q, r0) = g_cross.transpose();
    g_.block(r0, r0, q, q) = g_own;
    l_.block(r0, 0, q, r0) = x.transpose();
    l_.block(0, r0, r0, q).setZero();
    l_.block(r0, r0, q, q) = l22;
    a_.middleRows(r0, q) = change.a;
    y0_.middleRows(r0, q) = change.y0;
    terms_.push_back(std::move(term));
    rank_ = r0 + q;
    return true;
  }

  struct Term {
    int column = 0;         // first column of its block
    Eigen::MatrixXd v;      // its columns of V on its active dofs
    std::vector<int> rows;  // active index of each of those dofs
  };

  void reserve(int columns) {
    if (columns <= z_.cols()) return;
    const int capacity = std::min(max_rank_, std::max(columns, 2 * static_cast<int>(z_.cols())));
    const int old = rank_;
    z_.conservativeResize(static_cast<Eigen::Index>(active_dofs_.size()), capacity);
    Eigen::MatrixXd g = Eigen::MatrixXd::Zero(capacity, capacity), l = g;
    g.topLeftCorner(old, old) = g_.topLeftCorner(old, old);
    l.topLeftCorner(old, old) = l_.topLeftCorner(old, old);
    g_.swap(g);
    l_.swap(l);
    a_.conservativeResize(capacity, right_hand_sides());
    y0_.conservativeResize(capacity, right_hand_sides());
  }

  // The right-hand sides: the unit load, and the preload.
  Eigen::Index right_hand_sides() const { return preloaded_ ? 2 : 1; }

  void factor(Model& model) {
    factored_from_ = constraints_;
    preload_factored_from_ = preload_;
    history_.clear();
    system_ = std::make_unique<StaticSystem>(model, constraints_, settings_);
    ++factorizations_;
    constraints_ = system_->constraints();  // with the pins of the first factorization
    const Particles& p = model.particles;
    const int n = p.size();
    u0_.resize(kDofsPerParticle * n, right_hand_sides());
    for (Eigen::Index column = 0; column < right_hand_sides(); ++column) {
      if (column == 0)
        system_->solve(model, constraints_.value, false);  // the unit load alone
      else
        system_->solve(model, preload_, true);  // the preload and the free offsets
      u0_.col(column) = particle_state_vector(p);
    }
    const std::vector<int>& free = system_->free_dofs();
    free_count_ = static_cast<int>(free.size());
    free_of_dof_.assign(kDofsPerParticle * n, -1);
    for (int f = 0; f < free_count_; ++f) free_of_dof_[free[f]] = f;
    if (active_stale_) find_active_dofs(model);
    free_of_active_.resize(active_dofs_.size());
    for (std::size_t k = 0; k < active_dofs_.size(); ++k)
      free_of_active_[k] = free_of_dof_[active_dofs_[k]];
    rank_ = 0;
    terms_.clear();
    stale_ = false;
    capacity_at_factor_ = static_cast<long>(z_.cols());
  }

  // The free dofs connected, through the bonds' stiffness pattern, to a prescribed dof with a
  // non-zero value. Bonds only lose stiffness, so the pattern (and this set) holds until the
  // constraints change.
  void find_active_dofs(const Model& model) {
    const int dofs = kDofsPerParticle * model.particles.size();
    const int source = dofs;
    DisjointSets sets(dofs + 1);
    auto prescribed = [&](int dof) {
      return constraints_.fixed(dof / kDofsPerParticle, dof % kDofsPerParticle);
    };
    auto value = [&](int dof) {  // non-zero in either right-hand side
      const int i = dof / kDofsPerParticle, c = dof % kDofsPerParticle;
      return constraints_.value(i, c) != 0 || (preloaded_ && preload_(i, c) != 0);
    };
    for (int b = 0; b < model.bonds.size(); ++b) {
      if (model.bonds.is_broken(b)) continue;
      const std::array<int, 12> bd = bond_dofs(model.bonds, b);
      const Matrix12d k = symmetric_bond_stiffness(bond_parameters(model.bonds, b));
      const Eigen::Vector3d offset =
          preloaded_ ? Eigen::Vector3d(model.bonds.free_offset.row(b).transpose().matrix())
                     : Eigen::Vector3d::Zero();
      for (int r = 0; r < 12; ++r) {
        if (prescribed(bd[r])) continue;
        // The free offset's load K q^ (on the second particle's translation) reaches row r.
        if (k.row(r).segment<3>(6).dot(offset) != 0) sets.join(bd[r], source);
        for (int c = 0; c < 12; ++c) {
          if (k(r, c) == 0) continue;
          if (!prescribed(bd[c]))
            sets.join(bd[r], bd[c]);
          else if (value(bd[c]))
            sets.join(bd[r], source);
        }
      }
    }
    active_dofs_.clear();
    active_of_dof_.assign(dofs, -1);
    const int root = sets.find(source);
    for (int dof = 0; dof < dofs; ++dof)
      if (!prescribed(dof) && sets.find(dof) == root) {
        active_of_dof_[dof] = static_cast<int>(active_dofs_.size());
        active_dofs_.push_back(dof);
      }
    active_stale_ = false;
    z_.resize(0, 0);
    g_.resize(0, 0);
    l_.resize(0, 0);
    a_.resize(0, right_hand_sides());
    y0_.resize(0, right_hand_sides());
  }

  StaticSettings settings_;
  DofConstraints constraints_;
  DofArray preload_;  // the prescribed values at load factor 0 (preloaded_)
  bool preloaded_ = false;
  bool refactor_every_change_ = false;
  int max_rank_ = 0;
  std::unique_ptr<StaticSystem> system_;
  bool stale_ = true;
  bool active_stale_ = true;
  int factorizations_ = 0;
  int free_count_ = 0;
  Eigen::MatrixXd u0_;               // every dof, a column per right-hand side
  std::vector<int> free_of_dof_;     // dof -> free index of system_, or -1
  std::vector<int> active_dofs_;     // active index -> dof
  std::vector<int> active_of_dof_;   // dof -> active index, or -1
  std::vector<int> free_of_active_;  // active index -> free index
  int rank_ = 0;
  std::vector<Term> terms_;
  Eigen::MatrixXd z_, g_, l_;  // Z (active dofs x capacity), G and L (capacity x capacity)
  Eigen::MatrixXd a_, y0_;     // capacity x right_hand_sides()
  // For checkpoints: the constraints the last factorization was given, the columns its arrays
  // had then, and the changes since.
  DofConstraints factored_from_;
  DofArray preload_factored_from_;
  long capacity_at_factor_ = 0;
  std::vector<EventChange> history_;
};

// What one equilibrium at unit load gives.
struct UnitState {
  double energy = 0;           // strain energy at unit load [J]
  double reaction = 0;         // summed over the reaction dofs
  DofArray force;              // the bonds' generalized forces on each particle (force, torque)
  std::vector<double> factor;  // critical load factor of each bond (+inf: none)
  std::vector<BondState> mode;
  std::vector<double> ductility;    // kappa_u of each bond at this mix (softening_ductility)
  std::vector<double> bond_energy;  // each bond's strain energy at unit load [J]
  // With a preload (bond_events.hpp, "Preload"): the preload's state's energy, reaction and
  // forces, and the cross terms, so that the state at lambda holds
  // preload_energy + lambda cross_energy + lambda^2 energy (and so each bond).
  bool preloaded = false;
  double preload_energy = 0, cross_energy = 0, preload_reaction = 0;
  DofArray preload_force;
  std::vector<double> bond_preload_energy, bond_cross_energy;

  // The energy, the reaction and bond b's energy at load factor lambda.
  double energy_at(double lambda) const {
    return preload_energy + lambda * cross_energy + lambda * lambda * energy;
  }
  double reaction_at(double lambda) const { return preload_reaction + lambda * reaction; }
  double bond_energy_at(int b, double lambda) const {
    const auto k = static_cast<std::size_t>(b);
    if (!preloaded) return lambda * lambda * bond_energy[k];
    return bond_preload_energy[k] + lambda * bond_cross_energy[k] +
           lambda * lambda * bond_energy[k];
  }
};

// Whether a bond of `ductility` (its kappa_u at the unit solution's mix: softening_ductility)
// softens.
bool softening(double ductility) {
  return ductility > 1;
}

// Whether a softening bond's current tooth is its last (its next would be below the floor).
bool last_tooth(const Bonds& bonds, int b, const EventSettings& settings) {
  return (1.0 - bonds.damage(b)) * settings.tooth_stiffness_ratio < settings.last_tooth_stiffness;
}

// The utilisation at which bond b, of kappa_u `ductility`, fails next (see the file comment of
// bond_events.hpp).
double failure_kappa(const Bonds& bonds, int b, double ductility, const EventSettings& settings) {
  if (!softening(ductility) || bonds.damage(b) == 0) return 1.0;
  if (last_tooth(bonds, b, settings)) return ductility;
  return softening_ratio(bonds.damage(b), ductility);
}

// Adds a bond's response to the generalized forces on its ends.
void add_response(const BondResponse& r, int i, int j, DofArray& force) {
  for (int c = 0; c < 3; ++c) {
    force(i, c) += r.force_on_first(c);
    force(j, c) -= r.force_on_first(c);
    force(i, 3 + c) += r.torque_on_first(c);
    force(j, 3 + c) += r.torque_on_second(c);
  }
}

// Bond b's critical load factor under a preload: its stresses grow from those of the preload's
// state `p` (its free offset included) along those of the unit state `u` (without), and it fails
// where they reach U = kappa (bond_events.hpp, "Preload"); `unit` are its unit stresses.
CriticalLoad preloaded_critical_load(const Bonds& bonds, int b, const BondParameters& params,
                                     const Eigen::VectorXd& p, const Eigen::VectorXd& u,
                                     const BondStresses& unit, const BondStrength& strength,
                                     double kappa) {
  const int i = bonds.first(b), j = bonds.second(b);
  auto stresses_at = [&](double lambda) {
    return intact_stresses(bond_stresses(params, bonds.strength_radius(b),
                                         segment(p, i, 0) + lambda * segment(u, i, 0),
                                         segment(p, i, 3) + lambda * segment(u, i, 3),
                                         segment(p, j, 0) + lambda * segment(u, j, 0),
                                         segment(p, j, 3) + lambda * segment(u, j, 3)),
                           bonds.damage(b));
  };
  CriticalLoad c;
  c.factor = first_failure_factor(
      [&](double lambda) { return utilisation(stresses_at(lambda), strength).ratio / kappa; },
      critical_load(unit, strength, kappa).factor);
  if (!std::isfinite(c.factor)) return c;
  // The mode there: the law's own at that state (which reaches kappa at factor 1).
  const BondStresses at = stresses_at(c.factor);
  c.mode = critical_load(at, strength, kappa).mode;
  if (c.mode == BondState::kIntact) c.mode = utilisation(at, strength).mode;
  if (c.mode == BondState::kIntact) c.mode = BondState::kBrokenTension;
  return c;
}

// Bond b's responses at an equilibrium: to the unit solution `u` (without its free offset), and
// with a preload (`preloaded`, else null) to the preload's state (with it) and the cross term of
// its energy, so that its energy at lambda is preload + lambda cross + lambda^2 unit.
struct BondEquilibrium {
  BondParameters params, unit_params;  // the bond's, and without its free offset
  BondResponse unit, preload;
  double cross_energy = 0;
};

BondEquilibrium bond_equilibrium(const Bonds& bonds, int b, const Eigen::VectorXd& u,
                                 const Eigen::VectorXd* preloaded) {
  BondEquilibrium e;
  const int i = bonds.first(b), j = bonds.second(b);
  e.params = bond_parameters(bonds, b);
  e.unit_params = e.params;
  e.unit_params.free_offset.setZero();
  const Eigen::Vector3d ui = segment(u, i, 0), ti = segment(u, i, 3);
  const Eigen::Vector3d uj = segment(u, j, 0), tj = segment(u, j, 3);
  e.unit = parallel_bond_response(e.unit_params, ui, ti, uj, tj);
  if (!preloaded) return e;
  const Eigen::VectorXd& p = *preloaded;
  const Eigen::Vector3d pui = segment(p, i, 0), pti = segment(p, i, 3);
  const Eigen::Vector3d puj = segment(p, j, 0), ptj = segment(p, j, 3);
  e.preload = parallel_bond_response(e.params, pui, pti, puj, ptj);
  const double both =
      parallel_bond_response(e.params, pui + ui, pti + ti, puj + uj, ptj + tj).energy;
  e.cross_energy = both - e.preload.energy - e.unit.energy;
  return e;
}

// The unit-load equilibrium `u` (and with a preload its state `preloaded`, else null) into `s`:
// energies, forces, the reaction and each bond's critical load factor.
void evaluate(const Model& model, const Eigen::VectorXd& u, const Eigen::VectorXd* preloaded,
              const DofFlags& reaction_dofs, const EventSettings& settings, UnitState& s) {
  const Bonds& bonds = model.bonds;
  const int n = model.particles.size(), m = bonds.size();
  s.energy = 0;
  s.force = DofArray::Zero(n, kDofsPerParticle);
  s.factor.assign(m, std::numeric_limits<double>::infinity());
  s.mode.assign(m, BondState::kIntact);
  s.ductility.assign(m, 1.0);
  s.bond_energy.assign(m, 0.0);
  s.preloaded = preloaded != nullptr;
  if (s.preloaded) {
    s.preload_energy = s.cross_energy = 0;
    s.preload_force = DofArray::Zero(n, kDofsPerParticle);
    s.bond_preload_energy.assign(m, 0.0);
    s.bond_cross_energy.assign(m, 0.0);
  }
  for (int b = 0; b < m; ++b) {
    if (bonds.is_broken(b)) continue;
    const int i = bonds.first(b), j = bonds.second(b);
    const BondEquilibrium e = bond_equilibrium(bonds, b, u, preloaded);
    const BondParameters& params = e.params;  // its free offset with it
    const BondParameters& unit_params = e.unit_params;
    s.energy += e.unit.energy;
    s.bond_energy[b] = e.unit.energy;
    add_response(e.unit, i, j, s.force);
    if (s.preloaded) {
      const auto k = static_cast<std::size_t>(b);
      s.bond_preload_energy[k] = e.preload.energy;
      s.bond_cross_energy[k] = e.cross_energy;
      s.preload_energy += e.preload.energy;
      s.cross_energy += e.cross_energy;
      add_response(e.preload, i, j, s.preload_force);
    }
    const Eigen::Vector3d ui = segment(u, i, 0), ti = segment(u, i, 3);
    const Eigen::Vector3d uj = segment(u, j, 0), tj = segment(u, j, 3);
    if (!std::isfinite(bonds.tensile_strength(b)) && !std::isfinite(bonds.cohesion(b))) continue;
    const BondStresses stresses = intact_stresses(
        bond_stresses(unit_params, bonds.strength_radius(b), ui, ti, uj, tj), bonds.damage(b));
    const BondStrength strength = bond_strength(bonds, b);
    // kappa_u: Bonds::ductility, or for a mixed-mode bond that of the unit solution's mix, which
    // every load factor of this equilibrium shares.
    const double ductility = softening_ductility(stresses, strength);
    const double kappa = failure_kappa(bonds, b, ductility, settings);
    const CriticalLoad critical =
        s.preloaded
            ? preloaded_critical_load(bonds, b, params, *preloaded, u, stresses, strength, kappa)
            : critical_load(stresses, strength, kappa);
    if (critical.factor > 0 || (s.preloaded && critical.factor == 0)) {
      s.factor[b] = critical.factor;
      s.mode[b] = critical.mode;
      s.ductility[b] = ductility;
    }
  }
  // The support's reaction is K u on its dof: minus the bonds' generalized force there.
  s.reaction = -(s.force * reaction_dofs.cast<double>()).sum();
  if (s.preloaded) s.preload_reaction = -(s.preload_force * reaction_dofs.cast<double>()).sum();
}

// The strain energies of an equilibrium: at unit load (`u`), and with a preload (`preloaded`, or
// null) the preload's own and the cross term, so that the state at lambda holds
// preload + lambda cross + lambda^2 unit (as UnitState).
struct EquilibriumEnergies {
  double unit = 0, cross = 0, preload = 0;
};

EquilibriumEnergies equilibrium_energies(const Model& model, const Eigen::VectorXd& u,
                                         const Eigen::VectorXd* preloaded) {
  const Bonds& bonds = model.bonds;
  EquilibriumEnergies e;
  for (int b = 0; b < bonds.size(); ++b) {
    if (bonds.is_broken(b)) continue;
    const BondEquilibrium bond = bond_equilibrium(bonds, b, u, preloaded);
    e.unit += bond.unit.energy;
    e.preload += bond.preload.energy;
    e.cross += bond.cross_energy;
  }
  return e;
}

// The bond that fails next: the smallest finite critical factor, ties to the lowest index.
int critical_bond(const UnitState& s) {
  double smallest = std::numeric_limits<double>::infinity();
  for (double f : s.factor) smallest = std::min(smallest, f);
  if (!std::isfinite(smallest)) return -1;
  const double limit = smallest * (1 + kTieTolerance);
  for (std::size_t b = 0; b < s.factor.size(); ++b)
    if (s.factor[b] <= limit) return static_cast<int>(b);
  return -1;
}

// Writes the state lambda (u, force) into the particles.
void write_state(Particles& p, double lambda, const Eigen::VectorXd& u, const DofArray& force) {
  for (int i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      p.displacement(i, c) = lambda * u(kDofsPerParticle * i + c);
      p.rotation(i, c) = lambda * u(kDofsPerParticle * i + 3 + c);
      p.force(i, c) = lambda * force(i, c);
      p.torque(i, c) = lambda * force(i, 3 + c);
    }
}

// Writes the state of a preload (u_p, its forces) plus lambda (u, force) into the particles.
void write_state(Particles& p, double lambda, const Eigen::VectorXd& u, const DofArray& force,
                 const Eigen::VectorXd& preload_u, const DofArray& preload_force) {
  for (int i = 0; i < p.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      p.displacement(i, c) =
          preload_u(kDofsPerParticle * i + c) + lambda * u(kDofsPerParticle * i + c);
      p.rotation(i, c) =
          preload_u(kDofsPerParticle * i + 3 + c) + lambda * u(kDofsPerParticle * i + 3 + c);
      p.force(i, c) = preload_force(i, c) + lambda * force(i, c);
      p.torque(i, c) = preload_force(i, 3 + c) + lambda * force(i, 3 + c);
    }
}

// After a break: fixes the pieces that came loose (bond_events.hpp, "Pieces that come loose").
// `clusters` is the number of intact-bond clusters before the break. Returns whether
// `constraints` changed.
// With a preload (`preload_u` its state, non-null), the pieces are fixed where it put them at
// load factor 0 as well (into `preload`).
bool fix_loose_pieces(const Model& model, const Eigen::VectorXd& u, int& clusters,
                      DofConstraints& constraints, const Eigen::VectorXd* preload_u,
                      DofArray& preload) {
  std::vector<int> label;
  const int count = intact_clusters(model, label);
  if (count <= clusters) return false;
  clusters = count;
  const int n = model.particles.size();
  std::vector<std::vector<int>> members(count);
  std::vector<bool> held(count, false);
  for (int i = 0; i < n; ++i) {
    members[label[i]].push_back(i);
    if (constraints.fixed.row(i).any()) held[label[i]] = true;
  }
  bool changed = false;
  for (int k = 0; k < count; ++k) {
    if (members[k].size() == 1) {
      const int i = members[k].front();
      for (int c = 0; c < kDofsPerParticle; ++c)
        if (!constraints.fixed(i, c)) {
          constraints.fix(i, static_cast<Dof>(c), u(kDofsPerParticle * i + c));
          if (preload_u) preload(i, c) = (*preload_u)(kDofsPerParticle * i + c);
          changed = true;
        }
    } else if (!held[k]) {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero(), preload_mean = Eigen::Vector3d::Zero();
      for (int i : members[k]) mean += segment(u, i, 0);
      if (preload_u)
        for (int i : members[k]) preload_mean += segment(*preload_u, i, 0);
      mean /= static_cast<double>(members[k].size());
      preload_mean /= static_cast<double>(members[k].size());
      for (int i : members[k]) {
        constraints.fix_particle(i, mean, Eigen::Vector3d::Zero());
        if (!preload_u) continue;
        for (int c = 0; c < 3; ++c) {
          preload(i, c) = preload_mean(c);
          preload(i, 3 + c) = 0;
        }
      }
      changed = true;
    }
  }
  std::vector<int> intact;
  for (int b = 0; b < model.bonds.size(); ++b)
    if (!model.bonds.is_broken(b)) intact.push_back(b);
  Model held_together;
  held_together.particles = model.particles;
  held_together.bonds = model.bonds.select(intact);
  for (const PinnedDof& pin : rigid_mode_pins(held_together, constraints)) {
    constraints.fix(pin.particle, pin.dof, 0.0);
    if (preload_u) preload(pin.particle, static_cast<int>(pin.dof)) = 0;
    changed = true;
  }
  return changed;
}

// The event sequence of run_events (bond_events.hpp): the equilibrium at unit load, its critical
// state, the bond that fails there, and the stop rules; the unit-load solver keeps the factor up
// to date with the bonds' changes.
class EventLoop {
 public:
  EventLoop(Model& model, const DofConstraints& unit, const DofFlags& reaction_dofs,
            const EventSettings& settings, Clock::time_point start)
      : model_(model),
        reaction_dofs_(reaction_dofs),
        settings_(settings),
        start_(start),
        preloaded_(model.bonds.has_free_offsets() ||
                   (settings.preload.size() > 0 && (settings.preload != 0).any())),
        solver_(settings, unit,
                settings.preload.size() > 0
                    ? settings.preload
                    : DofArray(DofArray::Zero(model.particles.size(), kDofsPerParticle)),
                preloaded_) {
    std::vector<int> label;
    clusters_ = intact_clusters(model, label);
    const Bonds& bonds = model.bonds;
    for (int b = 0; b < bonds.size(); ++b) broken_ += bonds.is_broken(b) ? 1 : 0;
  }

  // Continues the run that saved `r` (EventSettings::on_checkpoint).
  void resume(const EventsState& r) {
    const int n = model_.particles.size();
    require(
        r.critical_u.size() == kDofsPerParticle * n && r.critical_force.rows() == n &&
            r.constraints.fixed.rows() == n && r.constraints.value.rows() == n &&
            (r.stale || (r.factored_from.fixed.rows() == n && r.factored_from.value.rows() == n)),
        fmt::format("events: the state to resume is for another model ({} particles here)", n));
    require(
        !preloaded_ || (r.preload.rows() == n && (r.stale || r.preload_factored_from.rows() == n) &&
                        (r.events == 0 || (r.critical_preload_u.size() == kDofsPerParticle * n &&
                                           r.critical_preload_force.rows() == n))),
        "events: the state to resume has no preload, and the model's bonds carry free offsets "
        "(or the settings a preload): it is another run's");
    result_.path = r.result.path;
    result_.breaks = r.result.breaks;
    result_.peak = r.result.peak;
    result_.solves = r.result.solves;
    result_.dissipated_energy = r.result.dissipated_energy;
    result_.crack_energy = r.result.crack_energy;
    result_.crack_area = r.result.crack_area;
    result_.crack_fracture_energy = r.result.crack_fracture_energy;
    result_.brittle_sites = r.result.brittle_sites;
    softening_ = r.softening;
    layer_energy_factors_.clear();
    for (const EventsState::LayerEnergyFactor& f : r.layer_energy_factors)
      layer_energy_factors_[{f.site, f.side}] = {f.factor, f.event};
    clusters_ = r.clusters;
    broken_ = r.broken;
    critical_u_ = r.critical_u;
    critical_preload_u_ = r.critical_preload_u;
    critical_preload_force_ = r.critical_preload_force;
    previous_preload_energy_ = r.previous_preload_energy;
    previous_cross_energy_ = r.previous_cross_energy;
    critical_force_ = r.critical_force;
    critical_lambda_ = r.critical_lambda;
    first_energy_ = r.first_energy;
    first_reaction_ = r.first_reaction;
    previous_energy_ = r.previous_energy;
    peak_reaction_ = r.peak_reaction;
    pending_stop_ = r.pending_stop;
    events_ = r.events;
    solver_.restore(model_, r);
  }

  EventsResult run() {
    while (true) {
      if (!solve()) break;
      ++result_.solves;
      evaluate(model_, u_, preloaded_ ? &preload_u_ : nullptr, reaction_dofs_, settings_, state_);
      if (events_ > 0) result_.dissipated_energy += released_energy();
      if (!pending_stop_.empty()) {
        result_.stop = pending_stop_;
        break;
      }
      if (first_energy_ < 0) {
        first_energy_ = state_.energy;
        first_reaction_ = std::abs(state_.reaction);
      }
      result_.final_stiffness_ratio = std::abs(state_.reaction) / first_reaction_;
      if (failed_at_material_point()) {
        result_.stop = "failed";
        break;
      }
      if (events_ > 0 && (state_.energy <= kCollapsedEnergy * first_energy_ ||
                          std::abs(state_.reaction) <= kCollapsedReaction * first_reaction_)) {
        result_.stop = "failed";
        break;
      }
      const int b = critical_bond(state_);
      const double bond_factor = b < 0 ? kNever : state_.factor[b];
      const Tooth tooth = critical_tooth();
      const SiteCrack site = critical_site();
      if (tooth.crack >= 0 && tooth.load_factor <= std::min(site.load_factor, bond_factor)) {
        after_event(soften(static_cast<std::size_t>(tooth.crack), tooth.load_factor));
        continue;
      }
      if (site.particle >= 0 && site.load_factor < bond_factor) {
        after_event(crack(site));
        continue;
      }
      if (b < 0) {
        result_.stop = "no bond loaded";
        break;
      }
      // The bond fails at the critical state: a tooth of stiffness, or all of it.
      const bool breaks = !softening(state_.ductility[b]) || last_tooth(model_.bonds, b, settings_);
      const EventPoint point = critical_state(b, state_.factor[b], breaks ? 1 : 0);
      lose_energy(point.load_factor * point.load_factor * state_.bond_energy[b] *
                  (breaks ? 1.0 : 1.0 - settings_.tooth_stiffness_ratio));
      fail(b, breaks, point, state_.mode[b]);
      after_event(point);
    }
    finish();
    return result_;
  }

 private:
  // The unit-load solution into u_; false (the run stopped) if a factorization after breaks
  // found a mechanism.
  bool solve() {
    if (events_ == 0) {
      solver_.solve(model_, u_, preload_u_);  // errors here are the caller's: bad constraints
      return true;
    }
    try {
      solver_.solve(model_, u_, preload_u_);
    } catch (const Error& e) {  // a factorization after breaks found a mechanism
      result_.stop = "failed";
      result_.message = e.what();
      result_.final_stiffness_ratio = 0;
      return false;
    }
    return true;
  }

  static constexpr double kNever = std::numeric_limits<double>::infinity();

  // The energy the last event released at fixed grips: the strain energy at its critical state
  // less that of the new equilibrium at the same load factor.
  double released_energy() const {
    const double l = critical_lambda_;
    const double unit = l * l * (previous_energy_ - state_.energy);
    if (!preloaded_) return unit;
    return (previous_preload_energy_ - state_.preload_energy) +
           l * (previous_cross_energy_ - state_.cross_energy) + unit;
  }

  // The particles at load factor lambda of the current equilibrium.
  void write_current_state(double lambda) {
    if (preloaded_)
      write_state(model_.particles, lambda, u_, state_.force, preload_u_, state_.preload_force);
    else
      write_state(model_.particles, lambda, u_, state_.force);
  }

  // A site whose crack opens next (material-point failure): the particle (-1: none), its load
  // factor, the bonds across its crack plane (normal `normal`) and how they break.
  struct SiteCrack {
    int particle = -1;
    double load_factor = kNever;
    std::vector<int> bonds;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitX();
    BondState mode = BondState::kBrokenTension;
    PlyFailureMode failure_mode = PlyFailureMode::kMatrixTension;
    double fracture_angle = 0;  // [rad]
    int tooth = 0;              // a softening crack's tooth (EventPoint::site_tooth)
    double area = -1;           // a layer's crack: its area [m^2] (-1: the site's share)
  };

  // The softening crack whose next tooth comes first: its index in softening_ (-1: none) and its
  // load factor.
  struct Tooth {
    int crack = -1;
    double load_factor = kNever;
  };

  // A softening crack's bonds not broken (they share one damage: each tooth changes them all).
  std::vector<int> unbroken(const SofteningCrack& c) const {
    std::vector<int> bonds;
    for (int b : c.bonds)
      if (!model_.bonds.is_broken(b)) bonds.push_back(b);
    return bonds;
  }

  // The strain energy of `bonds` (those not broken) at load factor lambda [J].
  double bonds_energy_at(const std::vector<int>& bonds, double lambda) const {
    if (!preloaded_) return lambda * lambda * bonds_energy(bonds);
    double e = 0;
    for (int b : bonds)
      if (!model_.bonds.is_broken(b)) e += state_.bond_energy_at(b, lambda);
    return e;
  }

  // The strain energy of `bonds` (those not broken) at the unit-load solution [J].
  double bonds_energy(const std::vector<int>& bonds) const {
    double e = 0;
    for (int b : bonds)
      if (!model_.bonds.is_broken(b)) e += state_.bond_energy[static_cast<std::size_t>(b)];
    return e;
  }

  // The next tooth of the softening cracks at the unit-load solution (ties: the lowest site, as
  // softening_ is ordered). A crack's kappa is sqrt(W / W_peak), W its bonds' energy at intact
  // stiffness (bond_events.hpp, "Softening sites"); its next tooth is where a softening bond of
  // its damage and ductility fails next (failure_kappa).
  Tooth critical_tooth() const {
    std::vector<double> factor(softening_.size(), kNever);
    double smallest = kNever;
    for (std::size_t k = 0; k < softening_.size(); ++k) {
      const SofteningCrack& c = softening_[k];
      const std::vector<int> bonds = unbroken(c);
      if (bonds.empty()) continue;
      const double stiffness = 1 - model_.bonds.damage(bonds.front());
      const double intact = bonds_energy(bonds) / stiffness;
      if (!(intact > 0)) continue;
      const double kappa = failure_kappa(model_.bonds, bonds.front(), c.ductility, settings_);
      if (preloaded_) {  // the intact energy, quadratic in lambda, reaches kappa^2 W_peak
        double pre = 0, cross = 0;
        for (int b : bonds) {
          pre += state_.bond_preload_energy[static_cast<std::size_t>(b)];
          cross += state_.bond_cross_energy[static_cast<std::size_t>(b)];
        }
        factor[k] = first_quadratic_crossing(pre / stiffness, cross / stiffness, intact,
                                             kappa * kappa * c.peak_energy);
      } else {
        factor[k] = kappa * std::sqrt(c.peak_energy / intact);
      }
      smallest = std::min(smallest, factor[k]);
    }
    Tooth tooth;
    for (std::size_t k = 0; k < factor.size() && tooth.crack < 0; ++k)
      if (factor[k] <= smallest * (1 + kTieTolerance)) tooth = {static_cast<int>(k), factor[k]};
    return tooth;
  }

  // Site `site`'s share of its crack plane (bond_events.hpp, "Softening sites") [m^2].
  double crack_share(const SiteCrack& site) const {
    if (site.area >= 0) return site.area;
    return plydem::crack_share(model_.particles, model_.bonds, site.particle, site.normal);
  }

  // The last event's bonds lost `energy` [J] as they changed (EventPoint::crack_energy).
  void lose_energy(double energy) {
    result_.path.back().crack_energy = energy;
    result_.crack_energy += energy;
  }

  // A site's crack of `area` [m^2], failed in `mode`, is open: its area and what it should have
  // dissipated.
  void count_open_crack(double area, PlyFailureMode mode) {
    result_.crack_area += area;
    result_.crack_fracture_energy += fracture_energy(mode) * area;
  }

  // The fracture energy of a site's crack in `mode` [J/m^2].
  double fracture_energy(PlyFailureMode mode) const {
    const LaminaStrength& strength = settings_.material_point->material.strength;
    const bool fibre =
        mode == PlyFailureMode::kFibreTension || mode == PlyFailureMode::kFibreCompression;
    return fibre ? strength.G_fibre : strength.G_matrix;
  }

  // The crack of a site that failed: its bonds open together, brittle or (softening) by their
  // first tooth; returns the event.
  EventPoint crack(const SiteCrack& site) {
    const double lambda = site.load_factor;
    const double energy = bonds_energy_at(site.bonds, lambda);  // W_peak
    const double area = crack_share(site);
    const double g = fracture_energy(site.failure_mode);
    const bool softening = settings_.material_point->softening;
    const double ductility = softening ? g * area / energy : 1.0;  // the line's kappa_u
    const int breaking = ductility > 1 ? 0 : static_cast<int>(site.bonds.size());
    const EventPoint point = critical_state(site.bonds.front(), lambda, breaking, &site);
    if (ductility > 1) {
      const double kept = settings_.tooth_stiffness_ratio;
      change_site(site.bonds, false, point, site.mode);
      lose_energy((1 - kept) * energy);
      SofteningCrack c;
      c.site = site.particle;
      c.bonds = site.bonds;
      c.normal = site.normal;
      c.mode = site.failure_mode;
      c.fracture_angle = site.fracture_angle;
      c.ductility = saw_tooth_ductility(ductility, settings_.tooth_stiffness_ratio,
                                        settings_.last_tooth_stiffness);
      c.peak_energy = energy;
      c.area = area;
      c.teeth = 1;
      const auto at =
          std::lower_bound(softening_.begin(), softening_.end(), c.site,
                           [](const SofteningCrack& x, int particle) { return x.site < particle; });
      softening_.insert(at, std::move(c));
    } else {
      if (softening) ++result_.brittle_sites;
      change_site(site.bonds, true, point, site.mode);
      lose_energy(energy);
      count_open_crack(area, site.failure_mode);
    }
    return point;
  }

  // Softening crack k's next tooth at load factor lambda: its bonds keep tooth_stiffness_ratio of
  // their stiffness, or break on the last; returns the event.
  EventPoint soften(std::size_t k, double lambda) {
    SofteningCrack& c = softening_[k];
    const std::vector<int> bonds = unbroken(c);
    const bool breaks = last_tooth(model_.bonds, bonds.front(), settings_);
    SiteCrack site;
    site.particle = c.site;
    site.failure_mode = c.mode;
    site.fracture_angle = c.fracture_angle;
    site.tooth = c.teeth;
    const int breaking = breaks ? static_cast<int>(bonds.size()) : 0;
    const EventPoint point = critical_state(bonds.front(), lambda, breaking, &site);
    const double energy = bonds_energy_at(bonds, lambda);
    change_site(bonds, breaks, point, crack_bond_state(c.mode));
    ++c.teeth;
    if (!breaks) {
      lose_energy((1 - settings_.tooth_stiffness_ratio) * energy);
      return point;
    }
    lose_energy(energy);
    count_open_crack(c.area, c.mode);
    softening_.erase(softening_.begin() + static_cast<std::ptrdiff_t>(k));
    return point;
  }

  // The site that fails first at the unit-load solution, passing over those whose crack is open
  // already (ties: the lowest particle index, within kTieTolerance).
  SiteCrack critical_site() {
    if (!settings_.material_point) return {};
    const MaterialPointFailure& mp = *settings_.material_point;
    std::vector<SiteFailure> sites = judged_sites(mp);
    if (mp.coupled) return critical_layer_crack(mp, sites);
    return site_crack(next_opening_site(model_.particles, model_.bonds, sites, kTieTolerance));
  }

  // Every site's failure at the current equilibrium (site_failures_now), less the sites that are
  // not judged: held by a grip, or beside a softening crack.
  std::vector<SiteFailure> judged_sites(const MaterialPointFailure& mp) {
    std::vector<SiteFailure> sites = site_failures_now(mp);
    // A particle whose translation is prescribed is held by a grip: its site does not fail (a
    // coupon's grips, like a test's tabs, are not its gauge).
    const DofFlags& held = solver_.constraints().fixed;
    for (int i = 0; i < model_.particles.size(); ++i) {
      if (held(i, static_cast<int>(Dof::kUx)) || held(i, static_cast<int>(Dof::kUy)))
        sites[static_cast<std::size_t>(i)].failure.load_factor = kNever;
    }
    // A site whose crack softens is not judged again until it has opened, nor are the sites its
    // crack's bonds reach, on the crack's other face: they read its opening through the bonds
    // that still bridge it beside them (the diagonals of the next site along the crack), and would
    // widen the crack into a band.
    for (const SofteningCrack& c : softening_) {
      sites[static_cast<std::size_t>(c.site)].failure.load_factor = kNever;
      for (int b : c.bonds) {  // both ends: a crack's bonds need not start at its site
        sites[static_cast<std::size_t>(model_.bonds.first(b))].failure.load_factor = kNever;
        sites[static_cast<std::size_t>(model_.bonds.second(b))].failure.load_factor = kNever;
      }
    }
    return sites;
  }

  // The crack of an opening site (none where opening.particle is -1).
  static SiteCrack site_crack(OpeningSite opening) {
    SiteCrack crack;
    if (opening.particle < 0) return crack;
    crack.particle = opening.particle;
    crack.load_factor = opening.site.failure.load_factor;
    crack.bonds = std::move(opening.bonds);
    crack.normal = opening.normal;
    crack.mode = crack_bond_state(opening.site.failure.mode);
    crack.failure_mode = opening.site.failure.mode;
    crack.fracture_angle = opening.site.failure.fracture_angle;
    return crack;
  }

  // Leguillon's coupled criterion (MaterialPointFailure::coupled): the sites in order of their
  // stress criterion's load factor; a fibre site's crack opens as it would alone, a matrix site's
  // crack runs through its layer (layer_crack) at the larger of its weakest site's stress factor
  // and the factor at which that crack releases its fracture energy (layer_energy_factor, one
  // factorization each). The first of those, ties to the first judged.
  //
  // A layer's energy factor found at an earlier event is kept as a lower bound of its current
  // one: cracks elsewhere shield it (it releases less at a given load once its neighbours have
  // cracked), so a layer whose bound is no smaller than the best crack found so far is passed
  // over, and the others are found again, in order of their bounds (lazy evaluation). Not an
  // exact bound, least of all after fibre breaks (bond_events.hpp, "Cracks through a layer",
  // says by how much and what it changes).
  SiteCrack critical_layer_crack(const MaterialPointFailure& mp, std::vector<SiteFailure>& sites) {
    SiteCrack best;
    std::vector<std::pair<double, SiteCrack>> deferred;  // (bound, layer crack)
    auto settle = [&](double below) {
      while (true) {
        auto first =
            std::min_element(deferred.begin(), deferred.end(),
                             [](const auto& a, const auto& b) { return a.first < b.first; });
        if (first == deferred.end() || !(first->first < below) ||
            !(first->first < best.load_factor))
          return;
        SiteCrack layer = std::move(first->second);
        deferred.erase(first);
        energy_factor_now(mp, layer);
        if (layer.load_factor < best.load_factor * (1 - kTieTolerance)) best = std::move(layer);
      }
    };
    while (true) {
      OpeningSite opening = next_opening_site(model_.particles, model_.bonds, sites, kTieTolerance);
      const double stress = opening.particle < 0 ? kNever : opening.site.failure.load_factor;
      settle(stress);
      if (opening.particle < 0 || stress > best.load_factor * (1 + kTieTolerance)) break;
      const PlyFailureMode mode = opening.site.failure.mode;
      if (mode == PlyFailureMode::kFibreTension || mode == PlyFailureMode::kFibreCompression) {
        if (stress < best.load_factor) best = site_crack(std::move(opening));
        break;  // every crack after it comes at a larger factor
      }
      SiteCrack layer = layer_crack(mp, site_crack(std::move(opening)), sites);
      if (layer.bonds.empty()) continue;
      const auto known = layer_energy_factors_.find(layer_key(layer));
      if (known != layer_energy_factors_.end() && known->second.second < events_) {
        deferred.emplace_back(std::max(stress, known->second.first), std::move(layer));
        continue;
      }
      energy_factor_now(mp, layer);
      if (layer.load_factor < best.load_factor * (1 - kTieTolerance)) best = std::move(layer);
    }
    return best;
  }

  // A layer crack's key: its first site and its normal's side.
  static std::pair<int, int> layer_key(const SiteCrack& layer) {
    const Eigen::Vector3d& n = layer.normal;
    const int axis = n.x() != 0 ? 0 : (n.y() != 0 ? 1 : 2);
    return {layer.particle, n(axis) > 0 ? axis + 1 : -(axis + 1)};
  }

  // Sets a layer crack's load factor: the larger of its stress factor and its energy factor at
  // the current equilibrium (found now, or earlier at this event).
  void energy_factor_now(const MaterialPointFailure& mp, SiteCrack& layer) {
    const std::pair<int, int> key = layer_key(layer);
    auto found = layer_energy_factors_.find(key);
    if (found == layer_energy_factors_.end() || found->second.second != events_) {
      const double factor =
          layer_energy_factor(layer.bonds, mp.material.strength.G_matrix * layer.area);
      found = layer_energy_factors_.insert_or_assign(key, std::make_pair(factor, events_)).first;
    }
    const std::pair<double, long>& known = found->second;
    layer.load_factor = std::max(layer.load_factor, known.first);
  }

  // The crack of `site` through its layer: the sites joined to it by intact bonds, in plies of
  // its ply's angle, on its crack plane (within a quarter of its radius along the normal), each
  // opening bonds_across_crack on the same side, with the interface bonds between those plies
  // that cross the plane; its area, the sites' shares. Its sites are not judged again in `sites`;
  // its particle is its first site (the lowest index), its load factor the site's.
  SiteCrack layer_crack(const MaterialPointFailure& mp, SiteCrack site,
                        std::vector<SiteFailure>& sites) {
    const Particles& p = model_.particles;
    const Bonds& bonds = model_.bonds;
    const Eigen::Vector3d n = site.normal;
    auto x = [&](int i) -> Eigen::Vector3d { return p.reference_position.row(i).transpose(); };
    auto angle = [&](int i) { return mp.ply_angles[static_cast<std::size_t>(p.ply(i))]; };
    const Eigen::Vector3d xs = x(site.particle);
    const double tolerance = 0.25 * p.radius(site.particle);
    std::vector<int> members{site.particle};
    std::vector<char> seen(static_cast<std::size_t>(p.size()), 0);
    seen[static_cast<std::size_t>(site.particle)] = 1;
    const std::vector<std::vector<std::pair<int, int>>>& near = neighbours();
    for (std::size_t k = 0; k < members.size(); ++k) {
      for (const auto& [j, b] : near[static_cast<std::size_t>(members[k])]) {
        if (seen[static_cast<std::size_t>(j)] || bonds.is_broken(b)) continue;
        if (angle(j) != angle(site.particle) || std::abs(n.dot(x(j) - xs)) > tolerance) continue;
        seen[static_cast<std::size_t>(j)] = 1;
        if (!std::isfinite(sites[static_cast<std::size_t>(j)].failure.load_factor)) continue;
        members.push_back(j);
      }
    }
    std::vector<int> across;
    double area = 0;
    std::vector<char> member_ply(static_cast<std::size_t>(p.ply.maxCoeff() + 1), 0);
    for (int m : members) {
      sites[static_cast<std::size_t>(m)].failure.load_factor = kNever;
      member_ply[static_cast<std::size_t>(p.ply(m))] = 1;
      const std::vector<int> own = bonds_across_crack(p, bonds, m, n);
      if (own.empty()) continue;
      across.insert(across.end(), own.begin(), own.end());
      area += plydem::crack_share(p, bonds, m, n);
    }
    for (int b = 0; b < bonds.size(); ++b) {
      if (!bonds.is_interface(b) || bonds.is_broken(b)) continue;
      const int i = bonds.first(b), j = bonds.second(b);
      if (!member_ply[static_cast<std::size_t>(p.ply(i))] ||
          !member_ply[static_cast<std::size_t>(p.ply(j))])
        continue;
      const double si = n.dot(x(i) - xs), sj = n.dot(x(j) - xs);
      if (std::min(si, sj) <= tolerance && std::max(si, sj) > tolerance) across.push_back(b);
    }
    std::erase_if(across, [&](int b) { return bonds.damage(b) > 0; });
    std::sort(across.begin(), across.end());
    across.erase(std::unique(across.begin(), across.end()), across.end());
    site.bonds = std::move(across);
    site.area = area;
    site.particle = *std::min_element(members.begin(), members.end());
    return site;
  }

  // The smallest load factor at which opening `across` (every bond, at fixed grips) releases
  // `target` [J]: the strain energy of the current equilibrium less that of the equilibrium
  // without those bonds, quadratic in the load factor. Never (+inf) where opening them would
  // leave a mechanism.
  double layer_energy_factor(const std::vector<int>& across, double target) {
    Bonds& bonds = model_.bonds;
    std::vector<std::array<double, 6>> saved(across.size());
    for (std::size_t k = 0; k < across.size(); ++k) {
      read_bond_fields(bonds, across[k], saved[k].data());
      open_bond(bonds, across[k], BondState::kBrokenTension);
    }
    double factor = 0;
    try {
      StaticSettings direct = settings_.static_settings;
      if (direct.method == StaticMethod::kAuto) direct.method = StaticMethod::kDirect;
      const StaticSystem system(model_, solver_.constraints(), direct);
      system.solve(model_, solver_.constraints().value, false);
      const Eigen::VectorXd u = particle_state_vector(model_.particles);
      Eigen::VectorXd pre;
      if (preloaded_) {
        system.solve(model_, solver_.preload(), true);
        pre = particle_state_vector(model_.particles);
      }
      const EquilibriumEnergies e = equilibrium_energies(model_, u, preloaded_ ? &pre : nullptr);
      factor =
          first_quadratic_crossing(state_.preload_energy - e.preload, state_.cross_energy - e.cross,
                                   state_.energy - e.unit, target);
    } catch (const Error&) {  // a mechanism: the layer's crack would leave a piece unheld
      factor = kNever;
    }
    for (std::size_t k = 0; k < across.size(); ++k)
      write_bond_fields(bonds, across[k], saved[k].data());
    return factor;
  }

  // Each particle's bonded neighbours (particle, bond), broken bonds included, built once.
  const std::vector<std::vector<std::pair<int, int>>>& neighbours() {
    if (neighbours_.empty()) {
      neighbours_.resize(static_cast<std::size_t>(model_.particles.size()));
      for (int b = 0; b < model_.bonds.size(); ++b) {
        const int i = model_.bonds.first(b), j = model_.bonds.second(b);
        neighbours_[static_cast<std::size_t>(i)].emplace_back(j, b);
        neighbours_[static_cast<std::size_t>(j)].emplace_back(i, b);
      }
    }
    return neighbours_;
  }

  // Every site's failure at the current equilibrium: as its unit-load stress scales, or with a
  // preload as its stress grows from the preload's along the unit load's.
  std::vector<SiteFailure> site_failures_now(const MaterialPointFailure& mp) {
    write_state(model_.particles, 1.0, u_, state_.force);
    if (!preloaded_)
      return site_failures(model_.particles, model_.bonds, mp.ply_angles, mp.criterion, mp.material,
                           mp.strength_factors);
    const std::vector<PlyStress> unit =
        site_ply_stresses(model_.particles, model_.bonds, mp.ply_angles, mp.material, {}, false);
    write_current_state(0.0);
    const std::vector<PlyStress> preload =
        site_ply_stresses(model_.particles, model_.bonds, mp.ply_angles, mp.material);
    return preloaded_site_failures(model_.particles, preload, unit, mp.ply_angles, mp.criterion,
                                   mp.material, mp.strength_factors);
  }

  // The critical state at load factor lambda at which bond b fails (with `breaking` bonds broken
  // in the event): logged in the path (and the peak), and shown to EventSettings::on_event.
  EventPoint critical_state(int b, double lambda, int breaking, const SiteCrack* site = nullptr) {
    ++events_;
    EventPoint point;
    if (site) {
      point.site = site->particle;
      point.site_mode = site->failure_mode;
      point.site_fracture_angle = site->fracture_angle;
      point.site_tooth = site->tooth;
    }
    point.event = events_;
    point.load_factor = lambda;
    point.reaction = state_.reaction_at(lambda);
    point.bond = b;
    point.strain_energy = state_.energy_at(lambda);
    critical_u_ = u_;
    critical_force_ = state_.force;
    critical_lambda_ = lambda;
    previous_energy_ = state_.energy;
    if (preloaded_) {
      critical_preload_u_ = preload_u_;
      critical_preload_force_ = state_.preload_force;
      previous_preload_energy_ = state_.preload_energy;
      previous_cross_energy_ = state_.cross_energy;
    }
    point.broken = broken_ + breaking;
    result_.path.push_back(point);
    const int index = static_cast<int>(result_.path.size()) - 1;
    if (result_.peak < 0 || std::abs(point.reaction) > peak_reaction_) {
      result_.peak = index;
      peak_reaction_ = std::abs(point.reaction);
    }
    if (settings_.on_event) {
      write_current_state(lambda);
      settings_.on_event(model_, point);
    }
    return point;
  }

  // Bond b breaks (all its stiffness, in `mode`) or loses a tooth, and the solver hears of the
  // change.
  void fail(int b, bool breaks, const EventPoint& point, BondState mode) {
    BondParameters removed;
    const EventChange change = change_bond(b, breaks, point, mode, removed);
    solver_.change(model_, b, removed, change);
  }

  // A site's crack: every bond across it breaks in `mode` (or, unless `breaks`, loses a tooth),
  // the solver updated for all of them at once.
  void change_site(const std::vector<int>& across, bool breaks, const EventPoint& point,
                   BondState mode) {
    std::vector<std::pair<int, BondParameters>> removed;
    std::vector<EventChange> records;
    for (int b : across) {
      BondParameters r;
      records.push_back(change_bond(b, breaks, point, mode, r));
      records.back().joins_previous = records.size() > 1;
      removed.emplace_back(b, r);
    }
    solver_.change_together(model_, removed, records);
  }

  // Bond b loses a tooth of stiffness or, with `breaks`, all of it (in `mode`): the model's bond
  // changed, the stiffness taken away into `removed`, and the change's record.
  EventChange change_bond(int b, bool breaks, const EventPoint& point, BondState mode,
                          BondParameters& removed) {
    Bonds& bonds = model_.bonds;
    const double r = settings_.tooth_stiffness_ratio;
    const BondParameters before = bond_parameters(bonds, b);
    EventChange change;
    change.bond = b;
    auto fields = [&](double* v) { read_bond_fields(bonds, b, v); };
    fields(change.before);
    const double keep = breaks ? 0.0 : r;
    removed = before;
    removed.normal_stiffness *= 1 - keep;
    removed.shear_stiffness *= 1 - keep;
    removed.bending_stiffness *= 1 - keep;
    removed.twisting_stiffness *= 1 - keep;
    if (breaks) {
      break_bond(b, point, mode);
    } else {
      bonds.normal_stiffness(b) *= r;
      bonds.shear_stiffness(b) *= r;
      bonds.bending_stiffness(b) *= r;
      bonds.twisting_stiffness(b) *= r;
      bonds.damage(b) = 1.0 - (1.0 - bonds.damage(b)) * r;
    }
    fields(change.after);
    change.removed[0] = removed.normal_stiffness;
    change.removed[1] = removed.shear_stiffness;
    change.removed[2] = removed.bending_stiffness;
    change.removed[3] = removed.twisting_stiffness;
    return change;
  }

  // Bond b breaks in `mode`: no stiffness left, logged at its contact point, and the pieces that
  // came loose are fixed.
  void break_bond(int b, const EventPoint& point, BondState mode) {
    Bonds& bonds = model_.bonds;
    open_bond(bonds, b, mode);
    ++broken_;
    BondBreak record;
    record.bond = b;
    record.mode = mode;
    record.at = static_cast<double>(point.event);
    record.load = point.load_factor;
    const int i = bonds.first(b);
    record.position = model_.particles.reference_position.row(i).transpose().matrix() +
                      bonds.lever_first(b) * bonds.normal.row(b).transpose().matrix();
    result_.breaks.push_back(record);
    DofConstraints constraints = solver_.constraints();
    DofArray preload = solver_.preload();
    if (fix_loose_pieces(model_, u_, clusters_, constraints, preloaded_ ? &preload_u_ : nullptr,
                         preload))
      solver_.set_constraints(constraints, preload);
  }

  // Progress, the stop rules that end the run at its next solve, and the checkpoint.
  void after_event(const EventPoint& point) {
    const double elapsed = seconds_since(start_);
    if (settings_.on_progress && elapsed - last_progress_ >= settings_.progress_seconds) {
      last_progress_ = elapsed;
      settings_.on_progress({events_, broken_, point.load_factor, peak_reaction_, elapsed});
    }
    // At the material point the stiffness decides too, at the next solve
    // (failed_at_material_point).
    if (!settings_.material_point && below_stop_fraction())
      pending_stop_ = "failed";
    else if (events_ >= settings_.max_events)
      pending_stop_ = "event limit";
    if (pending_stop_.empty() && settings_.stop_after)
      pending_stop_ = settings_.stop_after(model_, point);
    if (settings_.checkpoint_every > 0 && settings_.on_checkpoint &&
        events_ % settings_.checkpoint_every == 0)
      settings_.on_checkpoint(model_, checkpoint());
  }

  // After the peak, the last critical state's reaction is below stop_fraction of the peak's.
  bool below_stop_fraction() const {
    const int index = static_cast<int>(result_.path.size()) - 1;
    return index > result_.peak &&
           std::abs(result_.path.back().reaction) < settings_.stop_fraction * peak_reaction_;
  }

  // At the material point a site's crack opens at once, and a coupon's reaction at the critical
  // states dips far below its peak while a crack runs through a ply (the next site at its tip
  // fails at a fraction of the load), then recovers: a [0/90/0] plate's dipped to 0.46 of its
  // peak at 0.85% strain and went on to 2.9 times that peak. It has failed when its reaction is
  // below stop_fraction of the peak and its stiffness (the reaction at unit load, after the last
  // event) below stop_fraction of the intact coupon's too.
  bool failed_at_material_point() const {
    return settings_.material_point && events_ > 0 && below_stop_fraction() &&
           std::abs(state_.reaction) < settings_.stop_fraction * first_reaction_;
  }

  EventsState checkpoint() const {
    EventsState s;
    s.events = events_;
    s.broken = broken_;
    s.clusters = clusters_;
    s.critical_u = critical_u_;
    s.critical_force = critical_force_;
    s.critical_preload_u = critical_preload_u_;
    s.critical_preload_force = critical_preload_force_;
    s.previous_preload_energy = previous_preload_energy_;
    s.previous_cross_energy = previous_cross_energy_;
    s.critical_lambda = critical_lambda_;
    s.first_energy = first_energy_;
    s.first_reaction = first_reaction_;
    s.previous_energy = previous_energy_;
    s.peak_reaction = peak_reaction_;
    s.pending_stop = pending_stop_;
    s.result.path = result_.path;
    s.result.breaks = result_.breaks;
    s.result.peak = result_.peak;
    s.result.solves = result_.solves;
    s.result.dissipated_energy = result_.dissipated_energy;
    s.result.crack_energy = result_.crack_energy;
    s.result.crack_area = result_.crack_area;
    s.result.crack_fracture_energy = result_.crack_fracture_energy;
    s.result.brittle_sites = result_.brittle_sites;
    s.softening = softening_;
    for (const auto& [key, known] : layer_energy_factors_)
      s.layer_energy_factors.push_back({key.first, key.second, known.first, known.second});
    solver_.save(s);
    return s;
  }

  // Leaves the model at the last critical state (at the unit-load solution if no bond was
  // loaded).
  void finish() {
    if (events_ > 0 && preloaded_)
      write_state(model_.particles, critical_lambda_, critical_u_, critical_force_,
                  critical_preload_u_, critical_preload_force_);
    else if (events_ > 0)
      write_state(model_.particles, critical_lambda_, critical_u_, critical_force_);
    else
      write_current_state(1.0);
    result_.factorizations = solver_.factorizations();
    result_.softening_sites = static_cast<int>(softening_.size());
    result_.wall_seconds = seconds_since(start_);
    if (settings_.on_progress)
      settings_.on_progress(
          {events_, broken_, critical_lambda_, peak_reaction_, result_.wall_seconds});
  }

  Model& model_;
  const DofFlags& reaction_dofs_;
  const EventSettings& settings_;
  Clock::time_point start_;
  bool preloaded_ = false;  // bond_events.hpp, "Preload"
  UnitLoadSolver solver_;
  EventsResult result_;
  int clusters_ = 0;
  int broken_ = 0;
  long events_ = 0;
  Eigen::VectorXd u_;          // the unit-load solution
  Eigen::VectorXd preload_u_;  // the preload's state (preloaded_)
  UnitState state_;            // and what they give
  // The last critical state.
  Eigen::VectorXd critical_u_;
  DofArray critical_force_;
  Eigen::VectorXd critical_preload_u_;
  DofArray critical_preload_force_;
  double critical_lambda_ = 1, first_energy_ = -1, previous_energy_ = 0, peak_reaction_ = 0;
  double previous_preload_energy_ = 0, previous_cross_energy_ = 0;
  double first_reaction_ = 0;  // |reaction| of the first unit-load solution
  std::string pending_stop_;   // ends the run at the next solve
  double last_progress_ = 0;
  std::vector<SofteningCrack> softening_;  // the sites' cracks still softening, by site
  std::vector<std::vector<std::pair<int, int>>> neighbours_;  // neighbours(), built once
  // Each layer crack's energy factor (layer_key) and the event it was found at.
  std::map<std::pair<int, int>, std::pair<double, long>> layer_energy_factors_;
};

}  // namespace

EventsResult run_events(Model& model, const DofConstraints& unit, const DofFlags& reaction_dofs,
                        const EventSettings& settings, const EventsState* resume) {
  const auto start = Clock::now();
  settings.validate();
  const int n = model.particles.size();
  require(settings.preload.size() == 0 ||
              (settings.preload.rows() == n && settings.preload.cols() == kDofsPerParticle),
          fmt::format("events: the preload has {} x {} values for {} particles",
                      settings.preload.rows(), settings.preload.cols(), n));
  require(settings.preload.allFinite(), "events: the preload has a non-finite value");
  check_inputs(model, unit, reaction_dofs, settings.material_point.has_value());
  static std::once_flag said_ranks;  // once a process
  if (mpi_size() > 1)
    std::call_once(said_ranks, [] {
      spdlog::warn(
          "events: the event-by-event solver runs on one rank: under mpiexec each of the {} "
          "ranks runs it whole, the same events on every rank, and PETSc shares out only its "
          "static solves (the models are not split across ranks)",
          mpi_size());
    });
  EventLoop loop(model, unit, reaction_dofs, settings, start);
  if (resume) loop.resume(*resume);
  return loop.run();
}

namespace {

void write_constraints(CheckpointWriter& out, const DofConstraints& c) {
  out.u64(static_cast<std::uint64_t>(c.fixed.rows()));
  for (Eigen::Index i = 0; i < c.fixed.size(); ++i) out.boolean(c.fixed.data()[i]);
  out.doubles({c.value.data(), static_cast<std::size_t>(c.value.size())});
}

DofConstraints read_constraints(CheckpointReader& in) {
  const std::uint64_t rows = in.u64();
  if (rows > (1ull << 31)) in.corrupt(fmt::format("constraints for {} particles", rows));
  DofConstraints c(static_cast<int>(rows));
  for (Eigen::Index i = 0; i < c.fixed.size(); ++i) c.fixed.data()[i] = in.boolean();
  const std::vector<double> value = in.doubles();
  if (value.size() != static_cast<std::size_t>(c.value.size()))
    in.corrupt("the constraints' values have the wrong size");
  std::copy(value.begin(), value.end(), c.value.data());
  return c;
}

void write_dof_array(CheckpointWriter& out, const DofArray& a) {
  out.u64(static_cast<std::uint64_t>(a.rows()));
  out.doubles({a.data(), static_cast<std::size_t>(a.size())});
}

DofArray read_dof_array(CheckpointReader& in, const char* what) {
  const std::uint64_t rows = in.u64();
  if (rows > (1ull << 31)) in.corrupt(fmt::format("{} for {} particles", what, rows));
  const std::vector<double> values = in.doubles();
  if (values.size() != rows * kDofsPerParticle)
    in.corrupt(fmt::format("{} have the wrong size", what));
  DofArray a(static_cast<Eigen::Index>(rows), kDofsPerParticle);
  std::copy(values.begin(), values.end(), a.data());
  return a;
}

}  // namespace

void write_events_state(CheckpointWriter& out, const EventsState& s) {
  out.section("events");
  out.i64(s.events);
  out.i64(s.broken);
  out.i64(s.clusters);
  out.doubles({s.critical_u.data(), static_cast<std::size_t>(s.critical_u.size())});
  out.u64(static_cast<std::uint64_t>(s.critical_force.rows()));
  out.doubles({s.critical_force.data(), static_cast<std::size_t>(s.critical_force.size())});
  out.f64(s.critical_lambda);
  out.f64(s.first_energy);
  out.f64(s.first_reaction);
  out.f64(s.previous_energy);
  out.f64(s.peak_reaction);
  out.str(s.pending_stop);
  out.u64(s.result.path.size());
  for (const EventPoint& p : s.result.path) {
    out.i64(p.event);
    out.f64(p.load_factor);
    out.f64(p.reaction);
    out.i64(p.bond);
    out.i64(p.broken);
    out.f64(p.strain_energy);
    out.i64(p.site);
    out.i64(static_cast<int>(p.site_mode));
    out.f64(p.site_fracture_angle);
    out.i64(p.site_tooth);
    out.f64(p.crack_energy);
  }
  write_breaks(out, s.result.breaks);
  out.i64(s.result.peak);
  out.i64(s.result.solves);
  out.i64(s.result.factorizations);
  out.f64(s.result.dissipated_energy);
  out.f64(s.result.crack_energy);
  out.f64(s.result.crack_area);
  out.f64(s.result.crack_fracture_energy);
  out.i64(s.result.brittle_sites);
  write_constraints(out, s.constraints);
  out.boolean(s.stale);
  if (!s.stale) write_constraints(out, s.factored_from);
  out.boolean(s.active_stale);
  out.ints(s.active_dofs);
  out.i64(s.capacity);
  out.u64(s.changes.size());
  for (const EventChange& c : s.changes) {
    out.i64(c.bond);
    for (double v : c.before) out.f64(v);
    for (double v : c.after) out.f64(v);
    for (double v : c.removed) out.f64(v);
    out.boolean(c.joins_previous);
  }
  out.u64(s.softening.size());
  for (const SofteningCrack& c : s.softening) {
    out.i64(c.site);
    out.ints(c.bonds);
    out.doubles({c.normal.data(), 3});
    out.i64(static_cast<int>(c.mode));
    for (double v : {c.fracture_angle, c.ductility, c.peak_energy, c.area}) out.f64(v);
    out.i64(c.teeth);
  }
  // The preload (bond_events.hpp, "Preload"; empty arrays without one).
  out.doubles({s.critical_preload_u.data(), static_cast<std::size_t>(s.critical_preload_u.size())});
  write_dof_array(out, s.critical_preload_force);
  out.f64(s.previous_preload_energy);
  out.f64(s.previous_cross_energy);
  write_dof_array(out, s.preload);
  write_dof_array(out, s.preload_factored_from);
  out.u64(s.layer_energy_factors.size());
  for (const EventsState::LayerEnergyFactor& f : s.layer_energy_factors) {
    out.i64(f.site);
    out.i64(f.side);
    out.f64(f.factor);
    out.i64(f.event);
  }
}

EventsState read_events_state(CheckpointReader& in) {
  in.section("events");
  EventsState s;
  s.events = in.i64();
  s.broken = static_cast<int>(in.i64());
  s.clusters = static_cast<int>(in.i64());
  const std::vector<double> u = in.doubles();
  s.critical_u = Eigen::Map<const Eigen::VectorXd>(u.data(), static_cast<Eigen::Index>(u.size()));
  const std::uint64_t rows = in.u64();
  const std::vector<double> force = in.doubles();
  if (force.size() != rows * kDofsPerParticle)
    in.corrupt("the critical forces have the wrong size");
  s.critical_force.resize(static_cast<Eigen::Index>(rows), kDofsPerParticle);
  std::copy(force.begin(), force.end(), s.critical_force.data());
  s.critical_lambda = in.f64();
  s.first_energy = in.f64();
  s.first_reaction = in.f64();
  s.previous_energy = in.f64();
  s.peak_reaction = in.f64();
  s.pending_stop = in.str();
  const std::uint64_t points = in.u64();
  for (std::uint64_t k = 0; k < points; ++k) {
    EventPoint p;
    p.event = in.i64();
    p.load_factor = in.f64();
    p.reaction = in.f64();
    p.bond = static_cast<int>(in.i64());
    p.broken = static_cast<int>(in.i64());
    p.strain_energy = in.f64();
    p.site = static_cast<int>(in.i64());
    const std::int64_t mode = in.i64();
    if (mode < 0 || mode > static_cast<int>(PlyFailureMode::kMatrixCompression))
      in.corrupt("an event's site failure mode is out of range");
    p.site_mode = static_cast<PlyFailureMode>(mode);
    p.site_fracture_angle = in.f64();
    p.site_tooth = static_cast<int>(in.i64());
    p.crack_energy = in.f64();
    s.result.path.push_back(p);
  }
  s.result.breaks = read_breaks(in);
  s.result.peak = static_cast<int>(in.i64());
  s.result.solves = in.i64();
  s.result.factorizations = static_cast<int>(in.i64());
  s.result.dissipated_energy = in.f64();
  s.result.crack_energy = in.f64();
  s.result.crack_area = in.f64();
  s.result.crack_fracture_energy = in.f64();
  s.result.brittle_sites = static_cast<int>(in.i64());
  s.constraints = read_constraints(in);
  s.stale = in.boolean();
  if (!s.stale) s.factored_from = read_constraints(in);
  s.active_stale = in.boolean();
  s.active_dofs = in.ints();
  s.capacity = in.i64();
  const std::uint64_t changes = in.u64();
  for (std::uint64_t k = 0; k < changes; ++k) {
    EventChange c;
    c.bond = static_cast<int>(in.i64());
    for (double& v : c.before) v = in.f64();
    for (double& v : c.after) v = in.f64();
    for (double& v : c.removed) v = in.f64();
    c.joins_previous = in.boolean();
    s.changes.push_back(c);
  }
  const std::uint64_t softening = in.u64();
  for (std::uint64_t k = 0; k < softening; ++k) {
    SofteningCrack c;
    c.site = static_cast<int>(in.i64());
    c.bonds = in.ints();
    const std::vector<double> normal = in.doubles();
    if (normal.size() != 3) in.corrupt("a softening crack's normal is not a 3-vector");
    c.normal = Eigen::Vector3d(normal[0], normal[1], normal[2]);
    const std::int64_t mode = in.i64();
    if (mode < 0 || mode > static_cast<int>(PlyFailureMode::kMatrixCompression))
      in.corrupt("a softening crack's failure mode is out of range");
    c.mode = static_cast<PlyFailureMode>(mode);
    c.fracture_angle = in.f64();
    c.ductility = in.f64();
    c.peak_energy = in.f64();
    c.area = in.f64();
    c.teeth = static_cast<int>(in.i64());
    s.softening.push_back(std::move(c));
  }
  const std::vector<double> preload_u = in.doubles();
  s.critical_preload_u = Eigen::Map<const Eigen::VectorXd>(
      preload_u.data(), static_cast<Eigen::Index>(preload_u.size()));
  s.critical_preload_force = read_dof_array(in, "the preload's critical forces");
  s.previous_preload_energy = in.f64();
  s.previous_cross_energy = in.f64();
  s.preload = read_dof_array(in, "the preload's values");
  s.preload_factored_from = read_dof_array(in, "the preload's factored values");
  const std::uint64_t layers = in.u64();
  for (std::uint64_t k = 0; k < layers; ++k) {
    EventsState::LayerEnergyFactor f;
    f.site = static_cast<int>(in.i64());
    f.side = static_cast<int>(in.i64());
    f.factor = in.f64();
    f.event = in.i64();
    if (f.site < 0 || f.side == 0 || std::abs(f.side) > 3)
      in.corrupt("a layer crack's site or side is out of range");
    s.layer_energy_factors.push_back(f);
  }
  if (s.events < 0 || s.capacity < 0 || s.result.path.size() != static_cast<std::size_t>(s.events))
    in.corrupt(
        fmt::format("an events state of {} events with {} points", s.events, s.result.path.size()));
  return s;
}

}  // namespace plydem
