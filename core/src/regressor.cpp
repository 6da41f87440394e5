// regressor.cpp — τ = Y(q, q̇, q̈) β(θ) for both kinetic-energy variants (regressor.h).
//
// The relative position of mass k seen from joint j is a sum of link vectors,
// o_{k+1} − o_j = Σ_{links a = j..k} λ_s v_s(q), where each link contributes a "symbol" s:
// its length parameter times a unit vector (λ = l_a) and/or its fixed offsets (λ = 1).
// The unit vectors depend only on q and the twists, never on θ, so substituting the sum into
// the equations of motion (dynamics.cpp) makes every torque a sum of m_k·λ_s·λ_r times a
// function of (q, q̇, q̈): one column of Y per distinct product.
#include "manipid/core/regressor.h"

#include "dynamics_kernels.h"  // sine_cosine
#include "frame_update.h"

#include <algorithm>
#include <cmath>

namespace manipid {
namespace {

// A link vector v_s with its first two time derivatives, in base coordinates.
struct Symbol {
  int link = 0;     // 0-based link (the mass it first moves)
  int length = -1;  // length parameter index, or -1 for the fixed offsets (λ = 1)
  Eigen::Vector3d value, rate, acceleration;
};

std::vector<ParameterProducts::LinkSymbol> link_symbols(const RobotModel& model) {
  std::vector<ParameterProducts::LinkSymbol> symbols;
  for (int a = 0; a < model.joint_count(); ++a) {
    const JointDescription& joint = model.joints[a];
    if (joint.length_role != LengthRole::none) symbols.push_back({a, a});
    const double fixed_a = joint.length_role == LengthRole::a ? 0.0 : joint.a;
    const double fixed_d = joint.length_role == LengthRole::d ? 0.0 : joint.d;
    if (fixed_a != 0.0 || fixed_d != 0.0) symbols.push_back({a, -1});
  }
  return symbols;
}

// A vector u fixed in a frame turning at ω with ω̇: u̇ = ω × u, ü = ω̇ × u + ω × (ω × u).
void add_attached(const Eigen::Vector3d& u, double scale, const Eigen::Vector3d& omega,
                  const Eigen::Vector3d& omega_rate, Symbol& symbol) {
  const Eigen::Vector3d rate = omega.cross(u);
  symbol.value += scale * u;
  symbol.rate += scale * rate;
  symbol.acceleration += scale * (omega_rate.cross(u) + omega.cross(rate));
}

// Kinematics that do not depend on θ: rotations, angular velocities and accelerations.
void rotational_kinematics(const RobotModel& model, DynamicsWorkspace& w, const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& qd,
                           const Eigen::Ref<const Eigen::VectorXd>& qdd) {
  const int n = model.joint_count();
  for (int k = 0; k < n; ++k) {
    detail::sine_cosine(q[k], w.joint_sin[k], w.joint_cos[k]);
  }
  for (int k = 1; k <= n; ++k) {
    detail::update_rotation(w.rotation[k - 1], w.joint_cos[k - 1], w.joint_sin[k - 1], w.twist_cos[k - 1], w.twist_sin[k - 1], w.rotation[k]);
    const Eigen::Vector3d z = w.rotation[k - 1].col(2);
    const Eigen::Vector3d& omega_prev = w.angular_velocity[k - 1];
    w.angular_velocity[k] = omega_prev + qd[k - 1] * z;
    w.angular_acceleration[k] = w.angular_acceleration[k - 1] + qdd[k - 1] * z + qd[k - 1] * omega_prev.cross(z);
  }
}

void fill_symbols(const RobotModel& model, const ParameterProducts& products, const DynamicsWorkspace& w,
                  std::vector<Symbol>& symbols) {
  symbols.resize(products.symbols.size());
  for (std::size_t i = 0; i < products.symbols.size(); ++i) {
    const auto [a, length] = products.symbols[i];
    const JointDescription& joint = model.joints[a];
    Symbol& symbol = symbols[i];
    symbol.link = a;
    symbol.length = length;
    symbol.value.setZero();
    symbol.rate.setZero();
    symbol.acceleration.setZero();
    // Offset d runs along z_a (turning with frame a); offset a along x_{a+1} (frame a+1).
    const Eigen::Vector3d z = w.rotation[a].col(2);
    const Eigen::Vector3d x = w.rotation[a + 1].col(0);
    if (length >= 0) {
      if (joint.length_role == LengthRole::a) add_attached(x, 1.0, w.angular_velocity[a + 1], w.angular_acceleration[a + 1], symbol);
      else add_attached(z, 1.0, w.angular_velocity[a], w.angular_acceleration[a], symbol);
    } else {
      const double fixed_a = joint.length_role == LengthRole::a ? 0.0 : joint.a;
      const double fixed_d = joint.length_role == LengthRole::d ? 0.0 : joint.d;
      if (fixed_d != 0.0) add_attached(z, fixed_d, w.angular_velocity[a], w.angular_acceleration[a], symbol);
      if (fixed_a != 0.0) add_attached(x, fixed_a, w.angular_velocity[a + 1], w.angular_acceleration[a + 1], symbol);
    }
  }
}

// Products are unordered: (first, second) and (second, first) share a slot.
int lookup_index(int n, int mass, int first, int second) {
  if (first > second) std::swap(first, second);
  return (mass * (n + 1) + (first + 1)) * (n + 1) + (second + 1);
}

}  // namespace

ParameterProducts parameter_products(const RobotModel& model) {
  const int n = model.joint_count();
  ParameterProducts products;
  products.joint_count = n;
  products.lookup.assign(static_cast<std::size_t>(n) * (n + 1) * (n + 1), -1);
  auto add = [&](int mass, int first, int second) {
    int& slot = products.lookup[lookup_index(n, mass, first, second)];
    if (slot >= 0) return;
    slot = products.size();
    // Stored with a single length in `first`, and first ≤ second when both are lengths.
    if (first < 0 || (second >= 0 && second < first)) std::swap(first, second);
    products.terms.push_back({mass, first, second});
  };
  products.symbols = link_symbols(model);
  const bool gravity = model.gravity.squaredNorm() > 0.0;
  for (int k = 0; k < n; ++k) {
    for (const auto& s : products.symbols) {
      if (s.link > k) continue;
      if (gravity) add(k, s.length, -1);
      for (const auto& r : products.symbols) {
        if (r.link <= k) add(k, s.length, r.length);
      }
    }
    if (model.joint_inertia_factor != 0.0) add(k, k, k);
  }
  const int symbol_count = static_cast<int>(products.symbols.size());
  products.pair_offsets.push_back(0);
  for (const auto& s : products.symbols) {
    for (int r = -1; r < symbol_count; ++r) {
      const int first_mass = r < 0 ? s.link : std::max(s.link, products.symbols[r].link);
      const int second = r < 0 ? -1 : products.symbols[r].length;
      for (int k = first_mass; k < n; ++k) {
        const int column = products.lookup[lookup_index(n, k, s.length, second)];
        if (column >= 0) products.pair_columns.push_back(column);  // gravity's are absent without gravity
      }
      products.pair_offsets.push_back(static_cast<int>(products.pair_columns.size()));
    }
  }
  return products;
}

int ParameterProducts::column(int mass, int first, int second) const {
  const int n = joint_count;
  if (mass < 0 || mass >= n || first < -1 || first >= n || second < -1 || second >= n) return -1;
  return lookup[lookup_index(n, mass, first, second)];
}

std::string ParameterProducts::name(int column) const {
  const Term& term = terms.at(column);
  // Appends rather than "m" + to_string(...): g++ 12 warns falsely on that at -O3 (bug 105329).
  std::string text = "m";
  text.append(std::to_string(term.mass + 1));
  if (term.first >= 0 && term.first == term.second) return text.append("*l").append(std::to_string(term.first + 1)).append("^2");
  if (term.first >= 0) text.append("*l").append(std::to_string(term.first + 1));
  if (term.second >= 0) text.append("*l").append(std::to_string(term.second + 1));
  return text;
}

Eigen::VectorXd ParameterProducts::evaluate(const Parameters& parameters) const {
  Eigen::VectorXd beta(size());
  for (int i = 0; i < size(); ++i) {
    const Term& term = terms[i];
    double value = parameters.mass[term.mass];
    if (term.first >= 0) value *= parameters.length[term.first];
    if (term.second >= 0) value *= parameters.length[term.second];
    beta[i] = value;
  }
  return beta;
}

Eigen::MatrixXd ParameterProducts::jacobian(const Parameters& parameters) const {
  const int n = joint_count;
  Eigen::MatrixXd result = Eigen::MatrixXd::Zero(size(), 2 * n);
  for (int i = 0; i < size(); ++i) {
    const Term& term = terms[i];
    const double m = parameters.mass[term.mass];
    const double a = term.first >= 0 ? parameters.length[term.first] : 1.0;
    const double b = term.second >= 0 ? parameters.length[term.second] : 1.0;
    result(i, term.mass) = a * b;
    if (term.first >= 0) result(i, n + term.first) += m * b;
    if (term.second >= 0) result(i, n + term.second) += m * a;
  }
  return result;
}

void regressor(const RobotModel& model, const ParameterProducts& products, DynamicsWorkspace& w,
               const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& qd,
               const Eigen::Ref<const Eigen::VectorXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y) {
  const int n = model.joint_count();
  if (q.size() != n || qd.size() != n || qdd.size() != n) {
    throw InputError("q", "state sizes do not match the model's " + std::to_string(n) + " joints");
  }
  if (Y.rows() != n || Y.cols() != products.size()) throw InputError("Y", "regressor has the wrong shape");
  thread_local std::vector<Symbol> symbols;
  thread_local std::vector<double> row;  // Y's row j, contiguous while its sums are formed
  rotational_kinematics(model, w, q, qd, qdd);
  fill_symbols(model, products, w, symbols);
  row.resize(static_cast<std::size_t>(products.size()));
  const int symbol_count = static_cast<int>(symbols.size());
  const int* const columns = products.pair_columns.data();
  const int* const offsets = products.pair_offsets.data();
  // Adds `value` to the column of m_k·λ_s·λ_r for every mass k that both symbols move (r = −1:
  // m_k·λ_s), the columns listed once per model by parameter_products.
  auto add_pair = [&](int s, int r, double value) {
    const int pair = s * (symbol_count + 1) + r + 1;
    for (int c = offsets[pair]; c < offsets[pair + 1]; ++c) row[static_cast<std::size_t>(columns[c])] += value;
  };
  const bool complete = model.kinetic_energy == KineticEnergy::complete;

  for (int j = 0; j < n; ++j) {
    std::fill(row.begin(), row.end(), 0.0);
    const Eigen::Vector3d axis = w.rotation[j].col(2);
    const Eigen::Vector3d axis_rate = w.angular_velocity[j].cross(axis);
    // Joint inertia J_j = c·m_j·l_j² sees q̈_j only.
    if (model.joint_inertia_factor != 0.0) row[static_cast<std::size_t>(products.lookup[lookup_index(n, j, j, j)])] += model.joint_inertia_factor * qdd[j];
    for (int s = 0; s < symbol_count; ++s) {
      if (symbols[s].link < j) continue;
      const Eigen::Vector3d arm = axis.cross(symbols[s].value);  // w_js = z_j × v_s
      // Gravity: −m_k λ_s w_js·g for every mass k the symbol moves.
      const double gravity = -arm.dot(model.gravity);
      if (gravity != 0.0) add_pair(s, -1, gravity);
      for (int r = 0; r < symbol_count; ++r) {
        if (complete) {
          // Newton: m_k λ_s λ_r (z_j × v_s)·v̈_r.
          add_pair(s, r, arm.dot(symbols[r].acceleration));
        } else if (symbols[r].link >= j) {
          // Paper: M_jj q̈_j + Ṁ_jj q̇_j, M_jj = Σ m_k |Σ_s λ_s w_js|².
          const Eigen::Vector3d arm_r = axis.cross(symbols[r].value);
          const Eigen::Vector3d arm_r_rate = axis_rate.cross(symbols[r].value) + axis.cross(symbols[r].rate);
          add_pair(s, r, arm.dot(arm_r) * qdd[j] + 2.0 * arm.dot(arm_r_rate) * qd[j]);
        }
      }
    }
    if (!complete) {
      // Paper: −½ Σ_{i≤j} ∂M_ii/∂q_j q̇_i², ∂M_ii/∂q_j = 2 Σ_k m_k Σ λ_s λ_r w_is·(z_i × w_jr)
      // with s among links i..k and r among links j..k.
      for (int r = 0; r < symbol_count; ++r) {
        if (symbols[r].link < j) continue;
        const Eigen::Vector3d arm_r = axis.cross(symbols[r].value);
        for (int i = 0; i <= j; ++i) {
          if (qd[i] == 0.0) continue;
          const Eigen::Vector3d axis_i = w.rotation[i].col(2);
          const Eigen::Vector3d turned = axis_i.cross(arm_r);
          for (int s = 0; s < symbol_count; ++s) {
            if (symbols[s].link < i) continue;
            add_pair(s, r, -axis_i.cross(symbols[s].value).dot(turned) * qd[i] * qd[i]);
          }
        }
      }
    }
    Y.row(j) = Eigen::Map<const Eigen::RowVectorXd>(row.data(), products.size());
  }
}

Eigen::MatrixXd regressor(const RobotModel& model, const ParameterProducts& products, const Eigen::VectorXd& q,
                          const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  DynamicsWorkspace workspace(model);
  Eigen::MatrixXd Y(model.joint_count(), products.size());
  regressor(model, products, workspace, q, qd, qdd, Y);
  return Y;
}

}  // namespace manipid
