// urdf.cpp — URDF text → robot::Model: urdfdom parses; chain, merging and checks here (robot/urdf.h).
#include "manipid/core/robot/urdf.h"

#include "manipid/core/errors.h"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>

namespace manipid::robot {
namespace {

/// The range of a link's mass (kg) and the largest inertia entry (kg·m²) a manipulator's URDF may give.
constexpr double kLightestLink = 1e-6;
constexpr double kHeaviestLink = 1e6;
constexpr double kLargestInertia = 1e6;

// ---- urdfdom's messages -------------------------------------------------------------------------------

std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  while (!text.empty() && (text.back() == ' ' || text.back() == '.')) text.pop_back();
  return text;
}

std::string join(const std::vector<std::string>& items, const char* separator = ", ") {
  std::string out;
  for (const std::string& item : items) {
    if (!out.empty()) out += separator;
    out += item;
  }
  return out;
}

/// Receives console_bridge's messages during one parse.
class LogCapture : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) {
      errors.push_back(one_line(text));
    } else if (level == console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      warnings.push_back(one_line(text));
    }
  }
  std::vector<std::string> errors, warnings;
};

/// console_bridge's handler and level are process-global: one parse at a time swaps them.
std::mutex console_bridge_mutex;

/// The element urdfdom's messages name ("joint [j3]", "Link [b]", "link 'a'"), a joint preferred; "urdf" if none.
std::string element_named_in(const std::vector<std::string>& messages) {
  static const std::regex pattern(R"((joint|link)\s*[\['"]([^\]'"]+)[\]'"])", std::regex::icase);
  std::string link;
  for (const std::string& message : messages) {
    for (auto it = std::sregex_iterator(message.begin(), message.end(), pattern); it != std::sregex_iterator(); ++it) {
      std::string kind = (*it)[1];
      std::transform(kind.begin(), kind.end(), kind.begin(), [](unsigned char c) { return std::tolower(c); });
      if (kind == "joint") return "joint " + (*it)[2].str();
      if (link.empty()) link = "link " + (*it)[2].str();
    }
  }
  return link.empty() ? "urdf" : link;
}

/// urdfdom's parse with its console output captured: any error it logs refuses the document, even one it
/// parses past (a malformed <inertial> would otherwise become a massless link). Its warnings are kept.
urdf::ModelInterfaceSharedPtr parse_quietly(const std::string& xml, std::vector<std::string>& warnings) {
  LogCapture capture;
  urdf::ModelInterfaceSharedPtr urdf;
  std::string exception;
  {
    std::lock_guard<std::mutex> lock(console_bridge_mutex);
    console_bridge::OutputHandler* const previous_handler = console_bridge::getOutputHandler();
    const console_bridge::LogLevel previous_level = console_bridge::getLogLevel();
    console_bridge::useOutputHandler(&capture);
    console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
    try {
      urdf = urdf::parseURDF(xml);
    } catch (const std::exception& error) {
      exception = one_line(error.what());
    } catch (...) {
      exception = "unknown exception from urdfdom";
    }
    console_bridge::setLogLevel(previous_level);
    console_bridge::useOutputHandler(previous_handler);
  }
  if (!exception.empty()) capture.errors.push_back(exception);
  if (!capture.errors.empty()) {
    throw InputError(element_named_in(capture.errors), "invalid URDF: " + join(capture.errors, "; "));
  }
  if (!urdf) throw InputError("urdf", "invalid URDF: urdfdom could not read it and said nothing more");
  for (const std::string& warning : capture.warnings) warnings.push_back("urdfdom: " + warning);
  return urdf;
}

// ---- numbers out of urdfdom ----------------------------------------------------------------------------

std::string format(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

bool finite(const Eigen::Ref<const Eigen::MatrixXd>& m) { return m.allFinite(); }

/// A urdfdom pose (its rotation is the quaternion it made from rpy) as a Placement; `field` names the owner.
Placement placement_of(const urdf::Pose& pose, const std::string& field, const char* what) {
  Placement placement;
  placement.translation = {pose.position.x, pose.position.y, pose.position.z};
  const Eigen::Quaterniond quaternion(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  placement.rotation = quaternion.toRotationMatrix();
  if (!finite(placement.translation) || !finite(placement.rotation)) {
    throw InputError(field, field + " has a non-finite " + what);
  }
  return placement;
}

/// A link's <inertial> as standard parameters in the link's frame, after checking it.
InertialParameters inertial_parameters(const urdf::Link& link, std::vector<std::string>& warnings) {
  const urdf::Inertial& inertial = *link.inertial;
  const std::string field = "link " + link.name;
  const Placement frame = placement_of(inertial.origin, field, "<inertial> <origin>");
  Eigen::Matrix3d inertia;  // about the centre of mass, in the inertial frame
  inertia << inertial.ixx, inertial.ixy, inertial.ixz,  //
      inertial.ixy, inertial.iyy, inertial.iyz,          //
      inertial.ixz, inertial.iyz, inertial.izz;
  if (!std::isfinite(inertial.mass) || !finite(inertia)) {
    throw InputError(field, field + " has a non-finite mass or inertia");
  }
  if (inertial.mass < 0.0) {
    throw InputError(field, field + " has a negative mass, " + format(inertial.mass) + " kg");
  }
  // Beyond any link a manipulator has (a milligram, a thousand tonnes; 0 is a massless link): such a
  // number is a slip, and as a prior it scales every fit absurdly (1e-300 kg gave inertias of 1e146).
  if (inertial.mass != 0.0 && !(inertial.mass >= kLightestLink && inertial.mass <= kHeaviestLink)) {
    throw InputError(field, field + " has a mass of " + format(inertial.mass) + " kg: a link weighs " +
                                format(kLightestLink) + " to " + format(kHeaviestLink) + " kg (0 for a massless link)");
  }
  if (inertia.cwiseAbs().maxCoeff() > kLargestInertia) {
    throw InputError(field, field + " has an inertia entry of " + format(inertia.cwiseAbs().maxCoeff()) +
                                " kg·m², beyond any manipulator link's (" + format(kLargestInertia) + ")");
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(inertia, Eigen::EigenvaluesOnly);
  const Eigen::Vector3d moments = eigen.eigenvalues();  // ascending
  const double tolerance = 1e-9 * moments.cwiseAbs().maxCoeff();
  if (moments[0] < -tolerance) {
    throw InputError(field, field + " has an inertia about its centre of mass that is not positive semi-definite: "
                                    "eigenvalue " + format(moments[0]) + " kg·m²");
  }
  if (moments[0] + moments[1] < moments[2] - tolerance) {
    warnings.push_back(field + ": principal moments of inertia " + format(moments[0]) + ", " + format(moments[1]) +
                       ", " + format(moments[2]) + " kg·m² break the triangle inequality (I1 + I2 ≥ I3): no rigid "
                       "body has this inertia");
  }
  // About the centre of mass in link axes (R I Rᵀ), then about the link's origin (parallel axis).
  const Eigen::Matrix3d inertia_link_axes = frame.rotation * inertia * frame.rotation.transpose();
  return InertialParameters::from_centre_of_mass(inertial.mass, frame.translation,
                                                 0.5 * (inertia_link_axes + inertia_link_axes.transpose()));
}

bool is_moving(const urdf::Joint& joint) { return joint.type != urdf::Joint::FIXED; }

const char* type_name(const urdf::Joint& joint) {
  switch (joint.type) {
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    case urdf::Joint::FIXED: return "fixed";
    default: return "unknown";
  }
}

/// Refuses a joint on the chain that the model cannot take: floating, planar, mimic.
void check_chain_joint(const urdf::Joint& joint) {
  const std::string field = "joint " + joint.name;
  if (joint.type != urdf::Joint::REVOLUTE && joint.type != urdf::Joint::CONTINUOUS &&
      joint.type != urdf::Joint::PRISMATIC && joint.type != urdf::Joint::FIXED) {
    throw InputError(field, field + " is " + type_name(joint) +
                                ": the chain takes revolute, continuous, prismatic and fixed joints only");
  }
  if (joint.mimic) {
    throw InputError(field, field + " mimics joint " + joint.mimic->joint_name +
                                ": mimic joints are not supported on the chain or in merged bodies");
  }
}

/// Moving joint k of the model from a URDF joint whose frame sits at `placement` in body k−1's frame.
Joint model_joint(const urdf::Joint& source, const Placement& placement, std::vector<std::string>& warnings) {
  const std::string field = "joint " + source.name;
  Joint joint;
  joint.name = source.name;
  joint.link = source.child_link_name;
  joint.type = source.type == urdf::Joint::PRISMATIC    ? JointType::prismatic
               : source.type == urdf::Joint::CONTINUOUS ? JointType::continuous
                                                         : JointType::revolute;
  joint.placement = placement;

  const Eigen::Vector3d axis(source.axis.x, source.axis.y, source.axis.z);
  if (!finite(axis)) throw InputError(field, field + " has a non-finite axis");
  const double norm = axis.stableNorm();  // (1e200 1e200 0): norm() overflows to ∞ and the axis to 0
  if (norm == 0.0) throw InputError(field, field + " has a zero axis");
  if (std::abs(norm - 1.0) > 1e-6) {
    warnings.push_back(field + ": axis (" + format(axis.x()) + " " + format(axis.y()) + " " + format(axis.z()) +
                       ") has norm " + format(norm) + "; normalised");
  }
  joint.axis = axis / norm;

  if (source.limits) {
    joint.limits.velocity = source.limits->velocity;
    joint.limits.effort = source.limits->effort;
    if (joint.type != JointType::continuous) {  // URDF: a continuous joint's lower and upper are ignored
      joint.limits.lower = source.limits->lower;
      joint.limits.upper = source.limits->upper;
    }
  }
  const JointLimits& limits = joint.limits;
  if (std::isnan(limits.lower) || std::isnan(limits.upper) || std::isnan(limits.velocity) || std::isnan(limits.effort)) {
    throw InputError(field, field + " has a limit that is not a number");
  }
  if (limits.lower > limits.upper) {
    throw InputError(field, field + " has its lower limit " + format(limits.lower) + " above its upper limit " +
                                format(limits.upper));
  }
  if (joint.type != JointType::continuous && limits.lower == limits.upper) {
    warnings.push_back(field + ": lower and upper limits are both " + format(limits.lower) +
                       " (missing lower/upper attributes default to 0): the joint has no range to move in");
  }
  if (source.dynamics) {
    joint.damping = source.dynamics->damping;
    joint.friction = source.dynamics->friction;
    if (!std::isfinite(joint.damping) || !std::isfinite(joint.friction)) {
      throw InputError(field, field + " has a non-finite <dynamics> damping or friction");
    }
    if (joint.damping < 0.0 || joint.friction < 0.0) {
      throw InputError(field, field + " has a negative <dynamics> " + (joint.damping < 0.0 ? "damping, " + format(joint.damping)
                                                                                          : "friction, " + format(joint.friction)) +
                                  ": friction takes energy out, never puts it in");
    }
  }
  if (joint.limits.velocity < 0.0) {
    throw InputError(field, field + " has a negative velocity limit, " + format(joint.limits.velocity));
  }
  if (source.limits && joint.limits.velocity == 0.0) {
    warnings.push_back(field + ": its <limit> velocity is 0: an excitation cannot move it (identification is not "
                       "affected); give the joint's real velocity limit");
  }
  return joint;
}

// ---- the tree ------------------------------------------------------------------------------------------

class Tree {
 public:
  explicit Tree(const urdf::ModelInterface& urdf) : urdf_(urdf) { check_is_tree(); }

  const urdf::Link& link(const std::string& name) const { return *urdf_.links_.at(name); }
  bool has_link(const std::string& name) const { return urdf_.links_.count(name) > 0; }
  const std::string& root() const { return urdf_.getRoot()->name; }

  std::vector<std::string> link_names() const {
    std::vector<std::string> names;
    for (const auto& entry : urdf_.links_) names.push_back(entry.first);
    return names;
  }

  /// The links of the subtree below (and including) `top`, depth first.
  std::vector<std::string> subtree(const std::string& top) const {
    std::vector<std::string> links, stack{top};
    while (!stack.empty()) {
      const std::string name = stack.back();
      stack.pop_back();
      links.push_back(name);
      const auto& children = link(name).child_joints;
      for (auto it = children.rbegin(); it != children.rend(); ++it) stack.push_back((*it)->child_link_name);
    }
    return links;
  }

  /// The joints from `top` down to `bottom`, in that order; empty if `bottom` is not below `top`
  /// (or is `top`).
  std::vector<const urdf::Joint*> path(const std::string& top, const std::string& bottom) const {
    std::vector<const urdf::Joint*> joints;
    for (std::string name = bottom; name != top;) {
      const urdf::JointSharedPtr& parent = link(name).parent_joint;
      if (!parent) return {};
      joints.push_back(parent.get());
      name = parent->parent_link_name;
    }
    std::reverse(joints.begin(), joints.end());
    return joints;
  }

 private:
  /// urdfdom accepts a link that is the child of two joints (it keeps the last), and a cycle of links that
  /// never reaches the root: both are kinematic loops.
  void check_is_tree() const {
    std::map<std::string, std::vector<std::string>> parents;
    for (const auto& [name, joint] : urdf_.joints_) parents[joint->child_link_name].push_back(name);
    for (const auto& [child, joints] : parents) {
      if (joints.size() > 1) {
        throw InputError("link " + child, "link " + child + " is the child of joints " + join(joints, " and ") +
                                              ": a kinematic loop (a URDF describes a tree)");
      }
    }
    std::set<std::string> reached;
    for (const std::string& name : subtree(root())) reached.insert(name);
    std::vector<std::string> unreached, loop_joints;
    for (const auto& [name, link] : urdf_.links_) {
      if (reached.count(name)) continue;
      unreached.push_back(name);
      if (link->parent_joint) loop_joints.push_back(link->parent_joint->name);
    }
    if (!unreached.empty()) {
      throw InputError("link " + unreached.front(),
                       "links " + join(unreached) + " are not reachable from the root link " + root() + ": joints " +
                           join(loop_joints) + " close a kinematic loop (a URDF describes a tree)");
    }
  }

  const urdf::ModelInterface& urdf_;
};

/// A link merged into a body, with its pose in the body's frame.
struct Member {
  const urdf::Link* link;
  Placement pose;
};

std::string pick_tip(const Tree& tree, const std::string& base) {
  std::vector<std::string> leaves;
  for (const std::string& name : tree.subtree(base)) {
    if (tree.link(name).child_joints.empty()) leaves.push_back(name);
  }
  if (leaves.size() > 1) {
    throw InputError("tip", "the URDF has " + std::to_string(leaves.size()) + " leaves below base link " + base +
                                " (" + join(leaves) + "): choose the tip link");
  }
  if (leaves.front() == base) throw InputError("base", "no joint hangs below base link " + base);
  return leaves.front();
}

Eigen::Vector3d gravity_in_base(const Tree& tree, const UrdfOptions& options, const std::string& base) {
  if (!finite(options.gravity)) throw InputError("gravity", "gravity has a non-finite component");
  if (options.gravity_frame == GravityFrame::base || base == tree.root()) return options.gravity;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // of the base's axes in the root's
  for (const urdf::Joint* joint : tree.path(tree.root(), base)) {
    if (is_moving(*joint)) {
      throw InputError("base", "base link " + base + " moves relative to the root link " + tree.root() +
                                   " (joint " + joint->name + " is " + type_name(*joint) +
                                   "), so gravity given in the root's frame has no fixed direction in the base's: "
                                   "give gravity in the base frame (GravityFrame::base)");
    }
    const std::string field = "joint " + joint->name;
    rotation = rotation * placement_of(joint->parent_to_joint_origin_transform, field, "<origin>").rotation;
  }
  return rotation.transpose() * options.gravity;
}

}  // namespace

void check_urdf_shape(const std::string& xml) {
  const std::size_t n = xml.size();
  const auto starts = [&xml](std::size_t at, const char* text) { return xml.compare(at, std::strlen(text), text) == 0; };
  // Where an element starts, for the message: line and column (1-based).
  const auto where = [&xml](std::size_t at) {
    const long line = 1 + std::count(xml.begin(), xml.begin() + static_cast<std::ptrdiff_t>(at), '\n');
    const std::size_t newline = xml.rfind('\n', at == 0 ? 0 : at - 1);
    const std::size_t column = newline == std::string::npos || at == 0 ? at + 1 : at - newline;
    return "line " + std::to_string(line) + ", column " + std::to_string(column);
  };
  const auto name_at = [&xml, n](std::size_t at) {
    std::size_t end = at;
    while (end < n && end - at < 64 && !std::isspace(static_cast<unsigned char>(xml[end])) && xml[end] != '>' &&
           xml[end] != '/') {
      ++end;
    }
    return xml.substr(at, end - at);
  };
  // From the '<' at `from`, the index just past the character at which `ends` (seeing every character
  // outside quoted values) returns true; n + 1 when the text ends first.
  const auto past_markup = [&xml, n](std::size_t from, auto&& ends) {
    char quote = 0;
    for (std::size_t at = from + 1; at < n; ++at) {
      const char c = xml[at];
      if (quote) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (ends(c)) {
        return at + 1;
      }
    }
    return n + 1;
  };
  int depth = 0;
  std::size_t i = 0;
  while (i < n) {
    if (xml[i] != '<') {
      ++i;
      continue;
    }
    // Skipped wholesale: what holds no elements. Unterminated: the parser says so.
    const auto skip_to = [&](const char* end, std::size_t from) {
      const std::size_t found = xml.find(end, from);
      return found == std::string::npos ? n : found + std::strlen(end);
    };
    if (starts(i, "<!--")) {
      i = skip_to("-->", i + 4);
    } else if (starts(i, "<![CDATA[")) {
      i = skip_to("]]>", i + 9);
    } else if (starts(i, "<?")) {
      i = skip_to("?>", i + 2);
    } else if (starts(i, "<!")) {  // <!DOCTYPE …>, with an internal subset in [ ] that may hold '>'
      int brackets = 0;
      i = past_markup(i, [&brackets](char c) {
        brackets += c == '[' ? 1 : c == ']' ? -1 : 0;
        return c == '>' && brackets <= 0;
      });
    } else if (starts(i, "</")) {
      depth = std::max(0, depth - 1);
      i = skip_to(">", i + 2);
    } else {
      // A start tag: attributes are the '=' outside quoted values; "/>" closes it at once.
      const std::size_t tag = i;
      int attributes = 0;
      i = past_markup(i, [&](char c) {
        if (c == '=' && ++attributes > kMaxUrdfAttributes) {
          throw InputError("urdf", "the element <" + name_at(tag + 1) + "> at " + where(tag) + " has more than " +
                                       std::to_string(kMaxUrdfAttributes) + " attributes; no URDF element needs that many");
        }
        return c == '>';
      });
      const bool closed = i <= n && xml[i - 2] == '/';  // "/>": no level opened
      if (!closed && ++depth > kMaxUrdfDepth) {
        throw InputError("urdf", "the element <" + name_at(tag + 1) + "> at " + where(tag) + " is nested " +
                                     std::to_string(depth) + " deep, more than the " + std::to_string(kMaxUrdfDepth) +
                                     " any URDF needs (robot > link > visual > geometry > mesh is 5)");
      }
    }
  }
}

ParsedUrdf parse_urdf(const std::string& xml, const UrdfOptions& options) {
  ParsedUrdf result;
  std::vector<std::string>& warnings = result.warnings;
  check_urdf_shape(xml);  // before the parser, which recurses per level and checks attributes pairwise
  const urdf::ModelInterfaceSharedPtr urdf = parse_quietly(xml, warnings);
  // urdfdom's links hold their children through shared_ptr: in a URDF with a kinematic loop (refused
  // below) they form a cycle that would never be freed. Cut the links' pointers when done, whatever happens.
  struct CutLinksOnExit {
    urdf::ModelInterface& urdf;
    ~CutLinksOnExit() {
      for (auto& entry : urdf.links_) {
        entry.second->child_links.clear();
        entry.second->child_joints.clear();
        entry.second->parent_joint.reset();
      }
    }
  } cut_links_on_exit{*urdf};
  const Tree tree(*urdf);

  for (const auto& [option, name] : {std::pair{"base", &options.base}, std::pair{"tip", &options.tip}}) {
    if (!name->empty() && !tree.has_link(*name)) {
      throw InputError(option, std::string(option) + " link '" + *name + "' is not in the URDF (its links: " +
                                   join(tree.link_names()) + ")");
    }
  }
  const std::string base = options.base.empty() ? tree.root() : options.base;
  const std::string tip = options.tip.empty() ? pick_tip(tree, base) : options.tip;
  if (tip == base) throw InputError("tip", "tip link " + tip + " is the base link: there is no chain between them");
  const std::vector<const urdf::Joint*> path = tree.path(base, tip);
  if (path.empty()) throw InputError("tip", "tip link " + tip + " is not below base link " + base);

  Model& model = result.model;
  model.name = urdf->getName();
  model.base_link = base;
  model.tip_link = tip;
  model.gravity = gravity_in_base(tree, options, base);

  // The chain: each moving joint starts a body; fixed joints add their child to the current one.
  std::vector<std::vector<Member>> members(1);  // members[b]: the links of body b (0: the world)
  members[0].push_back({&tree.link(base), Placement{}});
  std::set<const urdf::Joint*> on_chain;
  Placement pose;  // of the current link in its body's frame
  for (const urdf::Joint* joint : path) {
    check_chain_joint(*joint);
    on_chain.insert(joint);
    const std::string field = "joint " + joint->name;
    const Placement joint_pose = pose * placement_of(joint->parent_to_joint_origin_transform, field, "<origin>");
    if (is_moving(*joint)) {
      model.joints.push_back(model_joint(*joint, joint_pose, warnings));
      members.emplace_back();
      pose = Placement{};
    } else {
      pose = joint_pose;
    }
    members.back().push_back({&tree.link(joint->child_link_name), pose});
  }
  if (model.joints.empty()) {
    throw InputError("tip", "no moving joint between base link " + base + " and tip link " + tip);
  }
  model.tip_placement = pose;

  // Side branches: links hanging from a body through fixed joints join it; a moving joint off the chain
  // leaves everything beyond it out.
  for (std::size_t b = 0; b < members.size(); ++b) {
    for (std::size_t i = 0; i < members[b].size(); ++i) {
      const Member member = members[b][i];  // a copy: members[b] grows below
      for (const urdf::JointSharedPtr& joint : member.link->child_joints) {
        if (on_chain.count(joint.get())) continue;
        if (!is_moving(*joint)) {
          if (b > 0 && joint->mimic) check_chain_joint(*joint);  // a mimic tag on a merged joint: refused
          const Placement child_pose =
              member.pose * placement_of(joint->parent_to_joint_origin_transform, "joint " + joint->name, "<origin>");
          members[b].push_back({&tree.link(joint->child_link_name), child_pose});
        } else {
          warnings.push_back("joint " + joint->name + " (" + type_name(*joint) + ") is not on the chain from " + base +
                             " to " + tip + ": links " + join(tree.subtree(joint->child_link_name)) +
                             " are left out of the dynamics");
        }
      }
    }
  }

  // Bodies 1..n: merged inertial parameters in each body's frame.
  for (std::size_t b = 1; b < members.size(); ++b) {
    Body body;
    for (const Member& member : members[b]) {
      body.links.push_back(member.link->name);
      if (!member.link->inertial) {
        warnings.push_back("link " + member.link->name + " has no <inertial>: counted as massless");
        continue;
      }
      body.inertia += inertial_parameters(*member.link, warnings).expressed_in(member.pose);
    }
    model.bodies.push_back(std::move(body));
  }
  return result;
}

}  // namespace manipid::robot
