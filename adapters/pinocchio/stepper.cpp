// The Pinocchio adapter's fixed-step loop in C++: the same integrators as its Python
// loop (adapters/pinocchio/integrators.py: euler, rk4 = Runge-Kutta-Munthe-Kaas, rk4-naive),
// the same model (passed as Pinocchio's own serialization of the Python-built pin.Model),
// the same loads and spring-dampers (adapters/pinocchio/springs.py), with no Python call per step; generic over
// Pinocchio's joint variant (free, revolute, prismatic, spherical alike). Compiled on first use by
// adapters/pinocchio/native.py against the installed Pinocchio; called through ctypes.
#include <cmath>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/multibody.hpp>
#include <pinocchio/serialization.hpp>
#include <pinocchio/spatial.hpp>

namespace pin = pinocchio;
using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;

namespace {

enum Method { EULER = 0, RK4 = 1, RK4_NAIVE = 2 };
// dexp^-1 of the configuration space: identity (only revolute and prismatic joints) or the dIntegrate
// solve (see PinocchioModel.dexpinv_function for why not Jlog6).
enum Dexpinv { IDENTITY = 0, SOLVE = 2 };

struct WorldLoad {
  int joint;
  Eigen::Vector3d p_J, vec;  // point in the joint frame; force or torque in world axes
  bool torque;
};

struct Spring {  // adapters/pinocchio/springs.py SpringElement
  int joint_a, joint_b;
  Eigen::Vector3d p_a, p_b;  // the ends in their joints' frames
  double stiffness, damping, rest_length;
};

struct Stepper {
  const pin::Model& model;
  pin::Data data;
  Vec tau;
  pin::container::aligned_vector<pin::Force> fext, fconst;
  std::vector<WorldLoad> world;
  std::vector<Spring> springs;
  bool loads;
  int dexpinv_kind;
  Mat J;
  Vec tmp_q;

  Stepper(const pin::Model& m, bool has_loads, int kind)
      : model(m), data(m), tau(Vec::Zero(m.nv)), fext(m.njoints, pin::Force::Zero()),
        fconst(m.njoints, pin::Force::Zero()), loads(has_loads), dexpinv_kind(kind), J(m.nv, m.nv), tmp_q(m.nq) {}

  // A point p_E of joint j's frame: world position and velocity (after forwardKinematics(q, v)).
  void point(int j, const Eigen::Vector3d& p_E, Eigen::Vector3d& x, Eigen::Vector3d& xd) const {
    const Eigen::Matrix3d& R = data.oMi[j].rotation();
    x = data.oMi[j].translation() + R * p_E;
    xd = R * (data.v[j].linear() + data.v[j].angular().cross(p_E));
  }

  void add_force(int j, const Eigen::Vector3d& p_E, const Eigen::Vector3d& f_W) {
    if (j == 0) return;  // the universe's share moves nothing
    Eigen::Vector3d f_E = data.oMi[j].rotation().transpose() * f_W;
    fext[j] += pin::Force(f_E, p_E.cross(f_E));
  }

  Vec acc(const Vec& q, const Vec& v) {
    if (!loads) return pin::aba(model, data, q, v, tau);
    if (!springs.empty()) pin::forwardKinematics(model, data, q, v);
    else if (!world.empty()) pin::forwardKinematics(model, data, q);
    for (int i = 0; i < model.njoints; ++i) fext[i] = fconst[i];
    for (const auto& w : world) {
      const Eigen::Matrix3d& R_WJ = data.oMi[w.joint].rotation();
      Eigen::Vector3d local = R_WJ.transpose() * w.vec;
      if (w.torque)
        fext[w.joint] += pin::Force(Eigen::Vector3d::Zero(), local);
      else
        fext[w.joint] += pin::Force(local, w.p_J.cross(local));
    }
    for (const auto& sp : springs) {
      Eigen::Vector3d x_a, xd_a, x_b, xd_b;
      point(sp.joint_a, sp.p_a, x_a, xd_a);
      point(sp.joint_b, sp.p_b, x_b, xd_b);
      Eigen::Vector3d d = x_b - x_a;
      const double length = d.norm();
      Eigen::Vector3d e = d / length;
      const double tension = sp.stiffness * (length - sp.rest_length) + sp.damping * e.dot(xd_b - xd_a);
      add_force(sp.joint_a, sp.p_a, tension * e);
      add_force(sp.joint_b, sp.p_b, -tension * e);
    }
    return pin::aba(model, data, q, v, tau, fext);
  }

  Vec integrate(const Vec& q, const Vec& dv) {
    pin::integrate(model, q, dv, tmp_q);
    return tmp_q;
  }

  Vec dexpinv(const Vec& q, const Vec& theta, const Vec& vel) {
    if (dexpinv_kind == IDENTITY) return vel;
    J.setZero();  // dIntegrate writes each joint's diagonal block only (Python's comes zeroed)
    pin::dIntegrate(model, q, theta, J, pin::ARG1);
    return J.partialPivLu().solve(vel);
  }

  void euler(Vec& q, Vec& v, double h) {
    v += h * acc(q, v);
    q = integrate(q, h * v);
  }

  void rk4(Vec& q, Vec& v, double h) {  // Munthe-Kaas: stage tangents k_i, all from q
    const double hh = 0.5 * h;
    Vec a1 = acc(q, v);
    Vec v2 = v + hh * a1, th2 = hh * v;
    Vec k2 = dexpinv(q, th2, v2);
    Vec a2 = acc(integrate(q, th2), v2);
    Vec v3 = v + hh * a2, th3 = hh * k2;
    Vec k3 = dexpinv(q, th3, v3);
    Vec a3 = acc(integrate(q, th3), v3);
    Vec v4 = v + h * a3, th4 = h * k3;
    Vec k4 = dexpinv(q, th4, v4);
    Vec a4 = acc(integrate(q, th4), v4);
    const double h6 = h / 6.0;
    q = integrate(q, h6 * (v + 2.0 * (k2 + k3) + k4));
    v = v + h6 * (a1 + 2.0 * (a2 + a3) + a4);
  }

  void rk4_naive(Vec& q, Vec& v, double h) {  // stagewise integrate, no dexp^-1
    const double hh = 0.5 * h;
    Vec a1 = acc(q, v);
    Vec v2 = v + hh * a1;
    Vec a2 = acc(integrate(q, hh * v), v2);
    Vec v3 = v + hh * a2;
    Vec a3 = acc(integrate(q, hh * v2), v3);
    Vec v4 = v + h * a3;
    Vec a4 = acc(integrate(q, h * v3), v4);
    const double h6 = h / 6.0;
    q = integrate(q, h6 * (v + 2.0 * (v2 + v3) + v4));
    v = v + h6 * (a1 + 2.0 * (a2 + a3) + a4);
  }
};

// The loads and springs, from the arrays adapters/pinocchio/native.py packs.
void set_forces(Stepper& s, const double* const_forces, int n_world, const int* world_joint,
                const double* world_point, const double* world_vec, const int* world_torque, int n_springs,
                const int* spring_joints, const double* spring_points, const double* spring_params) {
  for (int i = 0; i < s.model.njoints; ++i)
    s.fconst[i] = pin::Force(Eigen::Map<const Eigen::Matrix<double, 6, 1>>(const_forces + 6 * i));
  for (int k = 0; k < n_world; ++k)
    s.world.push_back({world_joint[k], Eigen::Map<const Eigen::Vector3d>(world_point + 3 * k),
                       Eigen::Map<const Eigen::Vector3d>(world_vec + 3 * k), world_torque[k] != 0});
  for (int k = 0; k < n_springs; ++k)
    s.springs.push_back({spring_joints[2 * k], spring_joints[2 * k + 1],
                         Eigen::Map<const Eigen::Vector3d>(spring_points + 6 * k),
                         Eigen::Map<const Eigen::Vector3d>(spring_points + 6 * k + 3), spring_params[3 * k],
                         spring_params[3 * k + 1], spring_params[3 * k + 2]});
}

}  // namespace

extern "C" {

// Steps from sample to sample: steps[k] substeps between times[k] and times[k + 1].
// Q (n_samples x nq) and V (n_samples x nv), row-major, come filled with NaN; rows are
// written while the state stays finite. Returns 0, or 1 with a message in err (an
// exception: a blown-up state, as the Python loop treats it). *n_steps: steps taken.
// has_forces: loads or springs (the external forces are built at every evaluation).
int dalembert_pin_fixed(const char* model_text, int method, int dexpinv_kind, const double* q0, const double* v0,
                        int n_samples, const double* times, const long* steps, int has_forces,
                        const double* const_forces, int n_world, const int* world_joint, const double* world_point,
                        const double* world_vec, const int* world_torque, int n_springs, const int* spring_joints,
                        const double* spring_points, const double* spring_params, double* Q, double* V,
                        long* n_steps, char* err, int err_len) {
  *n_steps = 0;
  try {
    pin::Model model;
    model.loadFromString(std::string(model_text));
    Stepper s(model, has_forces != 0, dexpinv_kind);
    set_forces(s, const_forces, n_world, world_joint, world_point, world_vec, world_torque, n_springs, spring_joints,
               spring_points, spring_params);
    Vec q = Eigen::Map<const Vec>(q0, model.nq), v = Eigen::Map<const Vec>(v0, model.nv);
    Eigen::Map<Vec>(Q, model.nq) = q;
    Eigen::Map<Vec>(V, model.nv) = v;
    for (int k = 1; k < n_samples; ++k) {
      const long n = steps[k - 1];
      const double h = (times[k] - times[k - 1]) / double(n);
      for (long i = 0; i < n; ++i) {
        if (method == EULER) s.euler(q, v, h);
        else if (method == RK4) s.rk4(q, v, h);
        else s.rk4_naive(q, v, h);
      }
      *n_steps += n;
      if (!(q.allFinite() && v.allFinite())) break;
      Eigen::Map<Vec>(Q + k * model.nq, model.nq) = q;
      Eigen::Map<Vec>(V + k * model.nv, model.nv) = v;
    }
    return 0;
  } catch (const std::exception& e) {
    std::strncpy(err, e.what(), err_len - 1);
    err[err_len - 1] = '\0';
    return 1;
  }
}

// One evaluation of the loop's right-hand side: the accelerations (nv) at (q, v), with the same
// forces as dalembert_pin_fixed (the audit identifies the springs from it). Returns 0, or 1 with err.
int dalembert_pin_acc(const char* model_text, const double* q, const double* v, int has_forces,
                      const double* const_forces, int n_world, const int* world_joint, const double* world_point,
                      const double* world_vec, const int* world_torque, int n_springs, const int* spring_joints,
                      const double* spring_points, const double* spring_params, double* a, char* err, int err_len) {
  try {
    pin::Model model;
    model.loadFromString(std::string(model_text));
    Stepper s(model, has_forces != 0, IDENTITY);
    set_forces(s, const_forces, n_world, world_joint, world_point, world_vec, world_torque, n_springs, spring_joints,
               spring_points, spring_params);
    Eigen::Map<Vec>(a, model.nv) = s.acc(Eigen::Map<const Vec>(q, model.nq), Eigen::Map<const Vec>(v, model.nv));
    return 0;
  } catch (const std::exception& e) {
    std::strncpy(err, e.what(), err_len - 1);
    err[err_len - 1] = '\0';
    return 1;
  }
}

}  // extern "C"
