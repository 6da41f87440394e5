// kdl_reference.h — Orocos KDL chains and trees built straight from urdfdom: the tests' independent reference.
//
// Nothing here goes through manipid's Model: joint origins, axes, types and inertials are read from
// urdf::ModelInterface and handed to KDL, which does its own fixed-joint merging (Joint::None segments),
// its own parallel-axis shift (RigidBodyInertia takes the inertia about the centre of mass) and its own
// rotation of the inertial frame. A segment is a URDF joint with its child link:
//     Segment(child, Joint(origin.p, origin.M · axis), f_tip = origin, inertia of child in its frame).
#pragma once

#include <kdl/chain.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/tree.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Core>

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace manipid::robot::testing::kdl {

inline KDL::Frame frame(const urdf::Pose& pose) {
  return KDL::Frame(KDL::Rotation::Quaternion(pose.rotation.x, pose.rotation.y, pose.rotation.z, pose.rotation.w),
                    KDL::Vector(pose.position.x, pose.position.y, pose.position.z));
}

/// The link's <inertial> in its frame: mass, centre of mass at origin xyz, and the inertia about the centre
/// of mass rotated by origin rpy into the link's axes — the rotation done by KDL.
inline KDL::RigidBodyInertia inertia(const urdf::Link& link) {
  if (!link.inertial) return KDL::RigidBodyInertia::Zero();
  const urdf::Inertial& i = *link.inertial;
  const KDL::Frame origin = frame(i.origin);
  const KDL::RotationalInertia in_inertial_frame(i.ixx, i.iyy, i.izz, i.ixy, i.ixz, i.iyz);
  const KDL::RigidBodyInertia rotated = origin.M * KDL::RigidBodyInertia(0.0, KDL::Vector::Zero(), in_inertial_frame);
  return KDL::RigidBodyInertia(i.mass, origin.p, rotated.getRotationalInertia());
}

/// A URDF joint as a KDL joint; `armature` is KDL's joint inertia (τ += armature · q̈).
inline KDL::Joint joint(const urdf::Joint& j, double armature = 0.0) {
  const KDL::Frame origin = frame(j.parent_to_joint_origin_transform);
  const KDL::Vector axis = origin.M * KDL::Vector(j.axis.x, j.axis.y, j.axis.z);
  switch (j.type) {
    case urdf::Joint::REVOLUTE:
    case urdf::Joint::CONTINUOUS: return KDL::Joint(j.name, origin.p, axis, KDL::Joint::RotAxis, 1.0, 0.0, armature);
    case urdf::Joint::PRISMATIC: return KDL::Joint(j.name, origin.p, axis, KDL::Joint::TransAxis, 1.0, 0.0, armature);
    case urdf::Joint::FIXED: return KDL::Joint(j.name, KDL::Joint::None);
    default: throw std::invalid_argument("joint " + j.name + ": no KDL equivalent");
  }
}

inline KDL::Segment segment(const urdf::ModelInterface& model, const urdf::Joint& j, double armature = 0.0) {
  return KDL::Segment(j.child_link_name, joint(j, armature), frame(j.parent_to_joint_origin_transform),
                      inertia(*model.getLink(j.child_link_name)));
}

/// Parses with urdfdom, throwing if it fails.
inline urdf::ModelInterfaceSharedPtr parse(const std::string& xml) {
  urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(xml);
  if (!model) throw std::invalid_argument("urdfdom could not parse the test URDF");
  return model;
}

/// The chain of every URDF joint from `base` down to `tip`; `armature` per moving joint (or empty).
inline KDL::Chain chain(const urdf::ModelInterface& model, const std::string& base, const std::string& tip,
                        const std::vector<double>& armature = {}) {
  std::vector<const urdf::Joint*> joints;
  for (std::string link = tip; link != base;) {
    const urdf::JointSharedPtr& parent = model.getLink(link)->parent_joint;
    if (!parent) throw std::invalid_argument(tip + " is not below " + base);
    joints.push_back(parent.get());
    link = parent->parent_link_name;
  }
  std::reverse(joints.begin(), joints.end());
  KDL::Chain chain;
  std::size_t moving = 0;
  for (const urdf::Joint* j : joints) {
    const bool fixed = j->type == urdf::Joint::FIXED;
    chain.addSegment(segment(model, *j, fixed || armature.empty() ? 0.0 : armature.at(moving)));
    if (!fixed) ++moving;
  }
  return chain;
}

/// The whole URDF tree as a KDL tree rooted at the root link, children depth first (so a serial arm's
/// joints get KDL's joint numbers in chain order).
inline KDL::Tree tree(const urdf::ModelInterface& model) {
  KDL::Tree tree(model.getRoot()->name);
  std::vector<const urdf::Link*> stack{model.getRoot().get()};
  while (!stack.empty()) {
    const urdf::Link* link = stack.back();
    stack.pop_back();
    for (auto it = link->child_joints.rbegin(); it != link->child_joints.rend(); ++it) {
      if (!tree.addSegment(segment(model, **it), link->name)) throw std::invalid_argument("KDL refused " + (*it)->name);
      stack.push_back(model.getLink((*it)->child_link_name).get());
    }
  }
  return tree;
}

inline KDL::JntArray joint_array(const Eigen::VectorXd& v) {
  KDL::JntArray array(static_cast<unsigned int>(v.size()));
  array.data = v;
  return array;
}

/// KDL's chain RNEA τ(q, q̇, q̈) under gravity `gravity` (in the chain's base frame), no external wrenches.
/// Keeps the chain alive for its solver (KDL's solver holds a reference to it).
class ChainDynamics {
 public:
  ChainDynamics(KDL::Chain chain, const Eigen::Vector3d& gravity)
      : chain_(std::move(chain)),
        solver_(chain_, KDL::Vector(gravity.x(), gravity.y(), gravity.z())),
        q_(chain_.getNrOfJoints()), qd_(chain_.getNrOfJoints()), qdd_(chain_.getNrOfJoints()),
        tau_(chain_.getNrOfJoints()), wrenches_(chain_.getNrOfSegments(), KDL::Wrench::Zero()) {}
  ChainDynamics(const ChainDynamics&) = delete;
  ChainDynamics& operator=(const ChainDynamics&) = delete;

  int joint_count() const { return static_cast<int>(chain_.getNrOfJoints()); }

  /// In place, no allocation: for the bench.
  const KDL::JntArray& torque(const KDL::JntArray& q, const KDL::JntArray& qd, const KDL::JntArray& qdd) {
    if (solver_.CartToJnt(q, qd, qdd, wrenches_, tau_) < 0) throw std::runtime_error("KDL ChainIdSolver_RNE failed");
    return tau_;
  }
  Eigen::VectorXd torque(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
    q_.data = q;
    qd_.data = qd;
    qdd_.data = qdd;
    return torque(q_, qd_, qdd_).data;
  }

 private:
  KDL::Chain chain_;
  KDL::ChainIdSolver_RNE solver_;
  KDL::JntArray q_, qd_, qdd_, tau_;
  KDL::Wrenches wrenches_;
};

/// KDL's tree RNEA, the same way.
class TreeDynamics {
 public:
  TreeDynamics(KDL::Tree tree, const Eigen::Vector3d& gravity)
      : tree_(std::move(tree)), solver_(tree_, KDL::Vector(gravity.x(), gravity.y(), gravity.z())) {}
  TreeDynamics(const TreeDynamics&) = delete;
  TreeDynamics& operator=(const TreeDynamics&) = delete;

  Eigen::VectorXd torque(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
    KDL::JntArray tau(tree_.getNrOfJoints());
    if (solver_.CartToJnt(joint_array(q), joint_array(qd), joint_array(qdd), KDL::WrenchMap(), tau) < 0) {
      throw std::runtime_error("KDL TreeIdSolver_RNE failed");
    }
    return tau.data;
  }

 private:
  KDL::Tree tree_;
  KDL::TreeIdSolver_RNE solver_;
};

}  // namespace manipid::robot::testing::kdl
