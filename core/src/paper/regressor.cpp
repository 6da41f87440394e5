// regressor.cpp — τ = Y(q, q̇, q̈) β(θ) for both kinetic-energy variants (regressor.h).
//
// The relative position of mass k seen from joint j is a sum of link vectors,
// o_{k+1} − o_j = Σ_{links a = j..k} λ_s v_s(q), where each link contributes a "symbol" s:
// its length parameter times a unit vector (λ = l_a) and/or its fixed offsets (λ = 1).
// The unit vectors depend only on q and the twists, never on θ, so substituting the sum into
// the equations of motion (dynamics.cpp) makes every torque a sum of m_k·λ_s·λ_r times a
// function of (q, q̇, q̈): one column of Y per distinct product.
#include "manipid/core/paper/regressor.h"

#include "paper/dynamics_kernels.h"  // sine_cosine
#include "paper/frame_update.h"  // next_axes
#include "vector_clones.h"

#include <algorithm>
#include <cmath>
#include <type_traits>

namespace manipid {
namespace {

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

// The kernel below runs on one sample (T = double) or on four at once (T = Lanes4, GCC's vector
// extension: +, − and × act lane by lane exactly as on doubles, so four samples give what four
// calls give, bit for bit but for the sign of a zero). Three-vectors of T, with Eigen's meaning.
// GCC warns that passing such a vector by value changes the ABI without AVX; these functions
// are internal to this file, compiled together, and never cross an ABI boundary. They are all
// inlined (MANIPID_INLINE) into the one kernel of four samples, which is compiled for AVX2 too
// (vector_clones.h): there a Lanes4 is one register.
#pragma GCC diagnostic ignored "-Wpsabi"  // to the end: GCC warns where it emits the functions, there
using Lanes4 = double __attribute__((vector_size(32)));
// Where a T is stored. GCC aligns a 32-byte vector to 16 bytes without AVX but assumes 32 in the
// AVX2 clone, and drops an alignment attribute on a template argument: every Lanes4 kept in
// memory is in a Cell or a Vec3, aligned to its size by alignas.
template <typename T>
constexpr std::size_t kAlignment = sizeof(T) == 32 ? 32 : alignof(T);
template <typename T>
struct alignas(kAlignment<T>) Cell {
  T value;
};
#define MANIPID_INLINE [[gnu::always_inline]] inline

template <typename T>
struct alignas(kAlignment<T>) Vec3 {
  T x, y, z;
};
template <typename T>
MANIPID_INLINE Vec3<T> operator+(const Vec3<T>& a, const Vec3<T>& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
template <typename T>
MANIPID_INLINE Vec3<T> operator-(const Vec3<T>& a, const Vec3<T>& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
template <typename T, typename S>
MANIPID_INLINE Vec3<T> operator*(const S& k, const Vec3<T>& a) { return {k * a.x, k * a.y, k * a.z}; }
template <typename T>
MANIPID_INLINE Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
template <typename T>
MANIPID_INLINE T dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

template <typename T>
MANIPID_INLINE T splat(double value) {
  if constexpr (std::is_same_v<T, double>) {
    return value;
  } else {
    return T{value, value, value, value};
  }
}
// A term whose value is exactly zero in every sample adds nothing and is skipped.
MANIPID_INLINE bool all_zero(double value) { return value == 0.0; }
MANIPID_INLINE bool all_zero(Lanes4 value) { return value[0] == 0.0 && value[1] == 0.0 && value[2] == 0.0 && value[3] == 0.0; }

template <typename T>
MANIPID_INLINE void sine_cosine(T angle, T& sine, T& cosine) {
  if constexpr (std::is_same_v<T, double>) {
    detail::sine_cosine(angle, sine, cosine);
  } else {
    for (int lane = 0; lane < 4; ++lane) detail::sine_cosine(angle[lane], sine[lane], cosine[lane]);
  }
}

// A link vector v_s with its first two time derivatives, in base coordinates.
template <typename T>
struct Symbol {
  Vec3<T> value, rate, acceleration;
};

// The frames' axes (columns of R_k), angular velocities and accelerations, k = 0 (base) … n.
template <typename T>
struct Frame {
  Vec3<T> x, y, z, omega, omega_rate;
};

// A vector u fixed in a frame turning at ω with ω̇: u̇ = ω × u, ü = ω̇ × u + ω × (ω × u).
template <typename T, typename S>
MANIPID_INLINE void add_attached(const Vec3<T>& u, const S& scale, const Frame<T>& frame, Symbol<T>& symbol) {
  const Vec3<T> rate = cross(frame.omega, u);
  symbol.value = symbol.value + scale * u;
  symbol.rate = symbol.rate + scale * rate;
  symbol.acceleration = symbol.acceleration + scale * (cross(frame.omega_rate, u) + cross(frame.omega, rate));
}

// Kinematics that do not depend on θ: rotations (frame_update.h), angular velocities and
// accelerations, then the link vectors.
template <typename T>
MANIPID_INLINE void kinematics(const RobotModel& model, const ParameterProducts& products, const DynamicsWorkspace& w, const Cell<T>* q,
                const Cell<T>* qd, const Cell<T>* qdd, std::vector<Frame<T>>& frames, std::vector<Symbol<T>>& symbols) {
  const int n = model.joint_count();
  frames.resize(static_cast<std::size_t>(n) + 1);
  const T zero = splat<T>(0.0), one = splat<T>(1.0);
  frames[0] = {{one, zero, zero}, {zero, one, zero}, {zero, zero, one}, {zero, zero, zero}, {zero, zero, zero}};
  for (int k = 1; k <= n; ++k) {
    const Frame<T>& previous = frames[static_cast<std::size_t>(k) - 1];
    Frame<T>& frame = frames[static_cast<std::size_t>(k)];
    T s, c;
    sine_cosine(q[k - 1].value, s, c);
    detail::next_axes(previous.x, previous.y, previous.z, c, s, w.twist_cos[k - 1], w.twist_sin[k - 1], frame.x, frame.y,
                      frame.z);
    frame.omega = previous.omega + qd[k - 1].value * previous.z;
    frame.omega_rate = previous.omega_rate + qdd[k - 1].value * previous.z + qd[k - 1].value * cross(previous.omega, previous.z);
  }
  symbols.resize(products.symbols.size());
  for (std::size_t i = 0; i < products.symbols.size(); ++i) {
    const auto [a, length] = products.symbols[i];
    const JointDescription& joint = model.joints[a];
    Symbol<T>& symbol = symbols[i];
    symbol.value = symbol.rate = symbol.acceleration = {zero, zero, zero};
    // Offset d runs along z_a (turning with frame a); offset a along x_{a+1} (frame a+1).
    const Frame<T>& along_d = frames[static_cast<std::size_t>(a)];
    const Frame<T>& along_a = frames[static_cast<std::size_t>(a) + 1];
    if (length >= 0) {
      if (joint.length_role == LengthRole::a) add_attached(along_a.x, one, along_a, symbol);
      else add_attached(along_d.z, one, along_d, symbol);
    } else {
      const double fixed_a = joint.length_role == LengthRole::a ? 0.0 : joint.a;
      const double fixed_d = joint.length_role == LengthRole::d ? 0.0 : joint.d;
      if (fixed_d != 0.0) add_attached(along_d.z, fixed_d, along_d, symbol);
      if (fixed_a != 0.0) add_attached(along_a.x, fixed_a, along_a, symbol);
    }
  }
}

// Products are unordered: (first, second) and (second, first) share a slot.
int lookup_index(int n, int mass, int first, int second) {
  if (first > second) std::swap(first, second);
  return (mass * (n + 1) + (first + 1)) * (n + 1) + (second + 1);
}

// Y's rows at one sample (T = double) or four (Lanes4): row j's sums are formed in `row` (one T
// per column) and handed to emit(j, row) before row j + 1 begins.
template <typename T, typename Emit>
MANIPID_INLINE void regressor_kernel(const RobotModel& model, const ParameterProducts& products, const DynamicsWorkspace& w, const Cell<T>* q,
                      const Cell<T>* qd, const Cell<T>* qdd, Emit&& emit) {
  const int n = model.joint_count();
  thread_local std::vector<Frame<T>> frames;
  thread_local std::vector<Symbol<T>> symbols;
  thread_local std::vector<Cell<T>> row;
  kinematics(model, products, w, q, qd, qdd, frames, symbols);
  row.resize(static_cast<std::size_t>(products.size()));
  const int symbol_count = static_cast<int>(symbols.size());
  const int* const columns = products.pair_columns.data();
  const int* const offsets = products.pair_offsets.data();
  // Adds `value` to the column of m_k·λ_s·λ_r for every mass k that both symbols move (r = −1:
  // m_k·λ_s), the columns listed once per model by parameter_products.
  auto add_pair = [&](int s, int r, const T& value) {
    const int pair = s * (symbol_count + 1) + r + 1;
    for (int c = offsets[pair]; c < offsets[pair + 1]; ++c) row[static_cast<std::size_t>(columns[c])].value += value;
  };
  const Vec3<T> gravity_vector{splat<T>(model.gravity.x()), splat<T>(model.gravity.y()), splat<T>(model.gravity.z())};
  const bool complete = model.kinetic_energy == KineticEnergy::complete;

  for (int j = 0; j < n; ++j) {
    std::fill(row.begin(), row.end(), Cell<T>{splat<T>(0.0)});
    const Frame<T>& joint_frame = frames[static_cast<std::size_t>(j)];
    const Vec3<T> axis = joint_frame.z;
    const Vec3<T> axis_rate = cross(joint_frame.omega, axis);
    // Joint inertia J_j = c·m_j·l_j² sees q̈_j only.
    if (model.joint_inertia_factor != 0.0) {
      row[static_cast<std::size_t>(products.lookup[lookup_index(n, j, j, j)])].value += model.joint_inertia_factor * qdd[j].value;
    }
    for (int s = 0; s < symbol_count; ++s) {
      if (products.symbols[s].link < j) continue;
      const Vec3<T> arm = cross(axis, symbols[s].value);  // w_js = z_j × v_s
      // Gravity: −m_k λ_s w_js·g for every mass k the symbol moves.
      const T gravity = -dot(arm, gravity_vector);
      if (!all_zero(gravity)) add_pair(s, -1, gravity);
      for (int r = 0; r < symbol_count; ++r) {
        if (complete) {
          // Newton: m_k λ_s λ_r (z_j × v_s)·v̈_r.
          add_pair(s, r, dot(arm, symbols[r].acceleration));
        } else if (products.symbols[r].link >= j) {
          // Paper: M_jj q̈_j + Ṁ_jj q̇_j, M_jj = Σ m_k |Σ_s λ_s w_js|².
          const Vec3<T> arm_r = cross(axis, symbols[r].value);
          const Vec3<T> arm_r_rate = cross(axis_rate, symbols[r].value) + cross(axis, symbols[r].rate);
          add_pair(s, r, dot(arm, arm_r) * qdd[j].value + 2.0 * dot(arm, arm_r_rate) * qd[j].value);
        }
      }
    }
    if (!complete) {
      // Paper: −½ Σ_{i≤j} ∂M_ii/∂q_j q̇_i², ∂M_ii/∂q_j = 2 Σ_k m_k Σ λ_s λ_r w_is·(z_i × w_jr)
      // with s among links i..k and r among links j..k.
      for (int r = 0; r < symbol_count; ++r) {
        if (products.symbols[r].link < j) continue;
        const Vec3<T> arm_r = cross(axis, symbols[r].value);
        for (int i = 0; i <= j; ++i) {
          if (all_zero(qd[i].value)) continue;
          const Vec3<T> axis_i = frames[static_cast<std::size_t>(i)].z;
          const Vec3<T> turned = cross(axis_i, arm_r);
          for (int s = 0; s < symbol_count; ++s) {
            if (products.symbols[s].link < i) continue;
            add_pair(s, r, -dot(cross(axis_i, symbols[s].value), turned) * qd[i].value * qd[i].value);
          }
        }
      }
    }
    emit(j, row.data());
  }
}

// Y's rows at four samples, `state` holding their q, q̇, q̈ (joint k's at k, n + k, 2n + k), as
// Y holds them: column c of the block (4n values: sample s's row j at s·n + j) at out[c·4n …].
// Out of line, for SSE2 and for AVX2.
MANIPID_VECTOR_CLONES void regressor_four(const RobotModel& model, const ParameterProducts& products,
                                          const DynamicsWorkspace& w, const Cell<Lanes4>* state, double* out) {
  const int n = model.joint_count();
  const int p = products.size();
  regressor_kernel<Lanes4>(model, products, w, state, state + n, state + 2 * n, [&](int j, const Cell<Lanes4>* row) {
    for (int c = 0; c < p; ++c) {
      double* column = out + static_cast<std::ptrdiff_t>(c) * 4 * n + j;
      for (int lane = 0; lane < 4; ++lane) column[lane * n] = row[c].value[lane];
    }
  });
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
  // Contiguous copies: the kernel reads q, q̇, q̈ as arrays whatever stride the caller's have.
  thread_local std::vector<Cell<double>> state;
  state.resize(3 * static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    state[static_cast<std::size_t>(k)].value = q[k];
    state[static_cast<std::size_t>(n + k)].value = qd[k];
    state[static_cast<std::size_t>(2 * n + k)].value = qdd[k];
  }
  regressor_kernel<double>(model, products, w, state.data(), state.data() + n, state.data() + 2 * n,
                           [&](int j, const Cell<double>* row) {
                             for (int c = 0; c < products.size(); ++c) Y(j, c) = row[c].value;
                           });
}

void regressor_rows(const RobotModel& model, const ParameterProducts& products, DynamicsWorkspace& w,
                    const Eigen::Ref<const Eigen::MatrixXd>& q, const Eigen::Ref<const Eigen::MatrixXd>& qd,
                    const Eigen::Ref<const Eigen::MatrixXd>& qdd, Eigen::Ref<Eigen::MatrixXd> Y) {
  const int n = model.joint_count();
  const Eigen::Index samples = q.rows();
  if (q.cols() != n || qd.cols() != n || qdd.cols() != n || qd.rows() != samples || qdd.rows() != samples) {
    throw InputError("q", "state sizes do not match the model's " + std::to_string(n) + " joints");
  }
  if (Y.rows() != samples * n || Y.cols() != products.size()) throw InputError("Y", "regressor rows have the wrong shape");
  const Eigen::Index p = products.size();
  thread_local std::vector<Cell<Lanes4>> state;  // q, q̇, q̈ of four samples: joint k's at k, n + k, 2n + k
  state.resize(3 * static_cast<std::size_t>(n));
  thread_local Eigen::MatrixXd block;  // their 4n rows of Y
  block.resize(4 * n, p);
  Eigen::Index first = 0;
  for (; first + 4 <= samples; first += 4) {
    for (int k = 0; k < n; ++k) {
      for (int lane = 0; lane < 4; ++lane) {
        state[static_cast<std::size_t>(k)].value[lane] = q(first + lane, k);
        state[static_cast<std::size_t>(n + k)].value[lane] = qd(first + lane, k);
        state[static_cast<std::size_t>(2 * n + k)].value[lane] = qdd(first + lane, k);
      }
    }
    regressor_four(model, products, w, state.data(), block.data());
    Y.middleRows(first * n, 4 * n) = block;  // the four samples' rows are adjacent in Y
  }
  for (; first < samples; ++first) {  // the last one to three, one at a time
    regressor(model, products, w, q.row(first).transpose(), qd.row(first).transpose(), qdd.row(first).transpose(),
              Y.middleRows(first * n, n));
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
