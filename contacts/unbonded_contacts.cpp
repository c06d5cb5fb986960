#include "contacts/unbonded_contacts.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "contacts/cell_list.hpp"
#include "core/error.hpp"

namespace plydem {

void ContactSettings::validate() const {
  require(std::isfinite(skin) && skin > 0,
          fmt::format("the contact skin must be finite and > 0, got {}", skin));
  require(
      check_interval >= 1,
      fmt::format("the contact check interval must be at least one cycle, got {}", check_interval));
  require(
      std::isfinite(friction) && friction >= 0,
      fmt::format("the contact friction coefficient must be finite and >= 0, got {}", friction));
}

namespace {

double dot3(const double* a, const double* b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// a x b
void cross3(const double* a, const double* b, double* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

}  // namespace

std::uint64_t UnbondedContacts::key(int i, int j) const {
  const auto lo = static_cast<std::uint64_t>(std::min(i, j));
  const auto hi = static_cast<std::uint64_t>(std::max(i, j));
  return lo * static_cast<std::uint64_t>(particles_) + hi;
}

UnbondedContacts::UnbondedContacts(const Model& model, const Eigen::ArrayXd& intact_normal,
                                   const Eigen::ArrayXd& intact_shear, std::vector<int> index,
                                   const ContactSettings& settings, const ContactState& s)
    : settings_(settings), index_(std::move(index)) {
  settings.validate();
  const Particles& p = model.particles;
  const Bonds& bonds = model.bonds;
  particles_ = p.size();
  require(static_cast<int>(index_.size()) == particles_,
          fmt::format("contacts: {} array indices for {} particles", index_.size(), particles_));
  require(intact_normal.size() == bonds.size() && intact_shear.size() == bonds.size(),
          "contacts: one intact stiffness per bond is needed");
  reference_position_ = p.reference_position;
  radius_ = p.radius;
  min_radius_ = particles_ > 0 ? p.radius.minCoeff() : 0.0;
  bond_first_ = bonds.first;
  bond_second_ = bonds.second;
  bond_length_ = bonds.length;
  bond_lever_first_ = bonds.lever_first;
  bond_lever_second_ = bonds.lever_second;
  intact_normal_ = intact_normal;
  intact_shear_ = intact_shear;

  // Each particle's mean intact bond stiffness (the model's mean where it has none known).
  particle_normal_.setZero(particles_);
  particle_shear_.setZero(particles_);
  Eigen::ArrayXd count = Eigen::ArrayXd::Zero(particles_);
  double sum_normal = 0, sum_shear = 0;
  int known = 0;
  for (int b = 0; b < bonds.size(); ++b) {
    if (!(intact_normal(b) > 0)) continue;
    for (int end : {bonds.first(b), bonds.second(b)}) {
      particle_normal_(end) += intact_normal(b);
      particle_shear_(end) += intact_shear(b);
      count(end) += 1;
    }
    sum_normal += intact_normal(b);
    sum_shear += intact_shear(b);
    ++known;
  }
  const double mean_normal = known > 0 ? sum_normal / known : 0.0;
  const double mean_shear = known > 0 ? sum_shear / known : 0.0;
  for (int i = 0; i < particles_; ++i) {
    particle_normal_(i) = count(i) > 0 ? particle_normal_(i) / count(i) : mean_normal;
    particle_shear_(i) = count(i) > 0 ? particle_shear_(i) / count(i) : mean_shear;
  }

  bonded_.reserve(static_cast<std::size_t>(bonds.size()));
  for (int b = 0; b < bonds.size(); ++b) bonded_.push_back(key(bonds.first(b), bonds.second(b)));
  std::sort(bonded_.begin(), bonded_.end());
  for (int b = 0; b < bonds.size(); ++b)
    if (bonds.is_broken(b)) contacts_.push_back(broken_pair(b));
  std::sort(contacts_.begin(), contacts_.end(), [&](const auto& a, const auto& c) {
    return key(a.first, a.second) < key(c.first, c.second);
  });
  search(s);
}

UnbondedContact UnbondedContacts::broken_pair(int b) const {
  UnbondedContact c;
  c.first = bond_first_(b);
  c.second = bond_second_(b);
  c.bond = b;
  for (int k = 0; k < 3; ++k)
    c.branch[k] = reference_position_(c.second, k) - reference_position_(c.first, k);
  c.distance = bond_length_(b);
  c.lever_first = bond_lever_first_(b);
  c.lever_second = bond_lever_second_(b);
  const bool known = intact_normal_(b) > 0;
  c.normal_stiffness =
      known ? intact_normal_(b) : 0.5 * (particle_normal_(c.first) + particle_normal_(c.second));
  c.shear_stiffness =
      known ? intact_shear_(b) : 0.5 * (particle_shear_(c.first) + particle_shear_(c.second));
  return c;
}

void UnbondedContacts::add_broken_bond(int b) {
  require(b >= 0 && b < bond_first_.size(), fmt::format("contacts: no bond {}", b));
  const UnbondedContact c = broken_pair(b);
  const std::uint64_t k = key(c.first, c.second);
  const auto at = std::lower_bound(contacts_.begin(), contacts_.end(), k,
                                   [&](const UnbondedContact& a, std::uint64_t value) {
                                     return key(a.first, a.second) < value;
                                   });
  if (at != contacts_.end() && key(at->first, at->second) == k) return;  // already a candidate
  contacts_.insert(at, c);
}

void UnbondedContacts::search(const ContactState& s) {
  PositionArray position(particles_, 3);
  searched_at_.resize(particles_, 3);
  for (int i = 0; i < particles_; ++i)
    for (int c = 0; c < 3; ++c) {
      searched_at_(i, c) = s.displacement[c][index_[i]];
      position(i, c) = reference_position_(i, c) + searched_at_(i, c);
    }
  ++searches_;
  if (particles_ < 2) return;
  // The candidates of this search: broken-bond pairs (kept) and never-bonded pairs in reach.
  std::vector<UnbondedContact> next;
  for (const UnbondedContact& c : contacts_)
    if (c.bond >= 0) next.push_back(c);
  for (const auto& [i, j] : find_contact_pairs(position, radius_, 1.0 + settings_.skin)) {
    if (std::binary_search(bonded_.begin(), bonded_.end(), key(i, j))) continue;
    UnbondedContact c;
    c.first = i;
    c.second = j;
    for (int k = 0; k < 3; ++k) c.branch[k] = reference_position_(j, k) - reference_position_(i, k);
    c.distance = radius_(i) + radius_(j);
    c.lever_first = radius_(i);
    c.lever_second = radius_(j);
    c.normal_stiffness = 0.5 * (particle_normal_(i) + particle_normal_(j));
    c.shear_stiffness = 0.5 * (particle_shear_(i) + particle_shear_(j));
    next.push_back(c);
  }
  std::sort(next.begin(), next.end(), [&](const auto& a, const auto& c) {
    return key(a.first, a.second) < key(c.first, c.second);
  });
  // Pairs already in the list keep their springs.
  std::size_t old = 0;
  for (UnbondedContact& c : next) {
    const std::uint64_t k = key(c.first, c.second);
    while (old < contacts_.size() && key(contacts_[old].first, contacts_[old].second) < k) ++old;
    if (old < contacts_.size() && key(contacts_[old].first, contacts_[old].second) == k) {
      for (int q = 0; q < 3; ++q) c.spring[q] = contacts_[old].spring[q];
      c.overlap = contacts_[old].overlap;
    }
  }
  contacts_ = std::move(next);
}

long UnbondedContacts::check(const ContactState& s, double dt) {
  double moved2 = 0, speed2 = 0;
  for (int i = 0; i < particles_; ++i) {
    const int a = index_[i];
    double d2 = 0, v2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double d = s.displacement[c][a] - searched_at_(i, c);
      d2 += d * d;
      v2 += s.velocity[c][a] * s.velocity[c][a];
    }
    moved2 = std::max(moved2, d2);
    speed2 = std::max(speed2, v2);
  }
  const double allowance = settings_.skin * min_radius_;
  double moved = std::sqrt(moved2);
  if (moved > 0.5 * allowance) {
    search(s);
    moved = 0;
  }
  const double speed = std::sqrt(speed2);
  if (!(speed > 0 && dt > 0)) return settings_.check_interval;
  const double cycles = (allowance - moved) / (2.0 * speed * dt);
  if (!(cycles < static_cast<double>(settings_.check_interval))) return settings_.check_interval;
  return std::max(1L, static_cast<long>(cycles));
}

namespace {

// The contact law for one candidate at state `s` (see the header): updates its spring and
// overlap, adds slip losses to `friction`, and returns whether it touches, with its force on the
// first particle `f` and the normal `n`.
bool contact_law(UnbondedContact& contact, const ContactState& s, double dt, double mu, int i,
                 int j, double f[3], double n[3], double& friction) {
  double d[3];
  for (int c = 0; c < 3; ++c)
    d[c] = contact.branch[c] + (s.displacement[c][j] - s.displacement[c][i]);
  const double distance = std::sqrt(dot3(d, d));
  const double overlap = contact.distance - distance;
  if (!(overlap > 0) || !(distance > 0)) {
    friction += 0.5 * contact.shear_stiffness * dot3(contact.spring, contact.spring);
    for (double& x : contact.spring) x = 0;
    contact.overlap = 0;
    return false;
  }
  for (int c = 0; c < 3; ++c) n[c] = d[c] / distance;
  // The contact points' relative velocity, and its tangential part.
  double a[3], v[3], a_cross_n[3];
  for (int c = 0; c < 3; ++c)
    a[c] = contact.lever_first * s.angular_velocity[c][i] +
           contact.lever_second * s.angular_velocity[c][j];
  cross3(a, n, a_cross_n);
  for (int c = 0; c < 3; ++c) v[c] = (s.velocity[c][j] - s.velocity[c][i]) - a_cross_n[c];
  const double v_n = dot3(v, n);
  // The spring, turned into the current tangent plane with its length kept, then stretched.
  double* spring = contact.spring;
  const double length2 = dot3(spring, spring);
  if (length2 > 0) {
    const double s_n = dot3(spring, n);
    double t[3];
    for (int c = 0; c < 3; ++c) t[c] = spring[c] - s_n * n[c];
    const double t2 = dot3(t, t);
    const double scale = t2 > 0 ? std::sqrt(length2 / t2) : 0.0;
    for (int c = 0; c < 3; ++c) spring[c] = scale * t[c];
  }
  for (int c = 0; c < 3; ++c) spring[c] += dt * (v[c] - v_n * n[c]);
  const double normal_force = contact.normal_stiffness * overlap;
  const double limit = mu * normal_force;
  const double spring2 = dot3(spring, spring);
  const double shear_force = contact.shear_stiffness * std::sqrt(spring2);
  if (shear_force > limit) {
    const double scale = limit / shear_force;
    for (int c = 0; c < 3; ++c) spring[c] *= scale;
    friction += 0.5 * contact.shear_stiffness * spring2 * (1.0 - scale * scale);
  }
  contact.overlap = overlap;
  for (int c = 0; c < 3; ++c) f[c] = -normal_force * n[c] + contact.shear_stiffness * spring[c];
  return true;
}

double contact_energy(const UnbondedContact& c) {
  return c.overlap > 0 ? 0.5 * c.normal_stiffness * c.overlap * c.overlap +
                             0.5 * c.shear_stiffness * dot3(c.spring, c.spring)
                       : 0.0;
}

}  // namespace

void UnbondedContacts::apply(const ContactState& s, double dt, const ContactForces& out) {
  for (int k : touched_)
    for (int c = 0; c < 3; ++c) {
      out.force[c][k] = 0;
      out.torque[c][k] = 0;
    }
  touched_.clear();
  for (UnbondedContact& contact : contacts_) {
    const int i = index_[contact.first], j = index_[contact.second];
    double f[3], n[3];
    if (!contact_law(contact, s, dt, settings_.friction, i, j, f, n, friction_dissipation_))
      continue;
    double n_cross_f[3];
    cross3(n, f, n_cross_f);
    for (int c = 0; c < 3; ++c) {
      out.force[c][i] += f[c];
      out.force[c][j] -= f[c];
      out.torque[c][i] += contact.lever_first * n_cross_f[c];
      out.torque[c][j] += contact.lever_second * n_cross_f[c];
    }
    touched_.push_back(i);
    touched_.push_back(j);
  }
}

double UnbondedContacts::handover(int b, const ContactState& s, double dt) const {
  require(b >= 0 && b < bond_first_.size(), fmt::format("contacts: no bond {}", b));
  UnbondedContact contact = broken_pair(b);
  const int i = index_[contact.first], j = index_[contact.second];
  double f[3], n[3], friction = 0;
  if (!contact_law(contact, s, dt, settings_.friction, i, j, f, n, friction)) return 0;
  double n_cross_f[3];
  cross3(n, f, n_cross_f);
  double work = 0;  // over the step just made: du = v dt, dtheta = w dt
  for (int c = 0; c < 3; ++c)
    work += dt * (f[c] * (s.velocity[c][i] - s.velocity[c][j]) +
                  n_cross_f[c] * (contact.lever_first * s.angular_velocity[c][i] +
                                  contact.lever_second * s.angular_velocity[c][j]));
  return contact_energy(contact) + friction + 0.5 * work;
}

double UnbondedContacts::stored_energy() const {
  double energy = 0;
  for (const UnbondedContact& c : contacts_) energy += contact_energy(c);
  return energy;
}

int UnbondedContacts::touching() const {
  int count = 0;
  for (const UnbondedContact& c : contacts_) count += c.overlap > 0 ? 1 : 0;
  return count;
}

void UnbondedContacts::save(CheckpointWriter& out) const {
  out.section("contacts");
  out.u64(contacts_.size());
  for (const UnbondedContact& c : contacts_) {
    out.i64(c.first);
    out.i64(c.second);
    out.i64(c.bond);
    for (int k = 0; k < 3; ++k) out.f64(c.branch[k]);
    out.f64(c.distance);
    out.f64(c.lever_first);
    out.f64(c.lever_second);
    out.f64(c.normal_stiffness);
    out.f64(c.shear_stiffness);
    for (int k = 0; k < 3; ++k) out.f64(c.spring[k]);
    out.f64(c.overlap);
  }
  out.ints(touched_);
  out.array(searched_at_);
  out.f64(friction_dissipation_);
  out.i64(searches_);
}

void UnbondedContacts::restore(CheckpointReader& in) {
  in.section("contacts");
  const std::uint64_t n = in.u64();
  std::vector<UnbondedContact> contacts;
  for (std::uint64_t k = 0; k < n; ++k) {
    UnbondedContact c;
    c.first = static_cast<int>(in.i64());
    c.second = static_cast<int>(in.i64());
    c.bond = static_cast<int>(in.i64());
    if (c.first < 0 || c.first >= particles_ || c.second < 0 || c.second >= particles_ ||
        c.bond < -1 || c.bond >= bond_first_.size())
      in.corrupt(fmt::format("contact {} joins particles {} and {} (bond {})", k, c.first, c.second,
                             c.bond));
    for (double& v : c.branch) v = in.f64();
    c.distance = in.f64();
    c.lever_first = in.f64();
    c.lever_second = in.f64();
    c.normal_stiffness = in.f64();
    c.shear_stiffness = in.f64();
    for (double& v : c.spring) v = in.f64();
    c.overlap = in.f64();
    contacts.push_back(c);
  }
  std::vector<int> touched = in.ints();
  for (int i : touched)
    if (i < 0 || i >= static_cast<int>(index_.size()) + 64)
      in.corrupt(fmt::format("a touched contact index {} is out of range", i));
  Vector3Array searched_at;
  in.array(searched_at);
  if (searched_at.rows() != particles_)
    throw Error(fmt::format("checkpoint {}: its contacts are for {} particles, the model has {}",
                            in.file(), searched_at.rows(), particles_));
  contacts_ = std::move(contacts);
  touched_ = std::move(touched);
  searched_at_ = std::move(searched_at);
  friction_dissipation_ = in.f64();
  searches_ = in.i64();
}

}  // namespace plydem
