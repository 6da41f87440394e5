// urdf_writer.cpp — identified parameters written into the URDF document with TinyXML (robot/urdf_writer.h).
#include "manipid/core/robot/urdf_writer.h"

#include "manipid/core/errors.h"

#include <Eigen/Eigenvalues>
#include <tinyxml.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

namespace manipid::robot {
namespace {

/// Shortest text that reads back to the same double.
std::string round_trip_text(double value) {
  char text[32];
  for (int digits = 6; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

std::string triple(const Eigen::Vector3d& v) {
  return round_trip_text(v.x()) + " " + round_trip_text(v.y()) + " " + round_trip_text(v.z());
}

/// The document's <link name="..."> and <joint name="..."> elements.
std::map<std::string, TiXmlElement*> named_children(TiXmlElement* robot, const char* tag) {
  std::map<std::string, TiXmlElement*> found;
  for (TiXmlElement* element = robot->FirstChildElement(tag); element; element = element->NextSiblingElement(tag)) {
    if (const char* name = element->Attribute("name")) found[name] = element;
  }
  return found;
}

/// Replaces (or adds) `parent`'s first <tag> with `replacement`.
void replace_child(TiXmlElement* parent, const char* tag, const TiXmlElement& replacement) {
  if (TiXmlElement* old = parent->FirstChildElement(tag)) {
    parent->ReplaceChild(old, replacement);
  } else {
    parent->InsertEndChild(replacement);
  }
}

/// A body's <inertial> (its centre of mass as <origin xyz>, rpy 0; its inertia about it), or InputError("parameters")
/// naming `what` when a URDF cannot hold it: a mass ≤ 0, or an inertia about the centre of mass that is not
/// positive semi-definite.
TiXmlElement inertial_element(const InertialParameters& inertia, const std::string& what) {
  if (!(inertia.mass > 0.0)) {
    throw InputError("parameters", what + " has mass " + round_trip_text(inertia.mass) +
                                       " kg: a URDF holds only physical bodies; identify with the physical-consistency "
                                       "option");
  }
  const Eigen::Matrix3d about_com = inertia.inertia_about_centre_of_mass();
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(about_com, Eigen::EigenvaluesOnly).eigenvalues()[0];
  if (smallest < -1e-12 * std::max(1.0, about_com.trace())) {
    throw InputError("parameters", what + "'s inertia about its centre of mass is not positive semi-definite (smallest "
                                       "eigenvalue " + round_trip_text(smallest) + " kg m^2): a URDF holds only physical "
                                       "bodies; identify with the physical-consistency option");
  }
  TiXmlElement inertial("inertial");
  TiXmlElement origin("origin");
  origin.SetAttribute("xyz", triple(inertia.centre_of_mass()));
  origin.SetAttribute("rpy", "0 0 0");
  inertial.InsertEndChild(origin);
  TiXmlElement mass("mass");
  mass.SetAttribute("value", round_trip_text(inertia.mass));
  inertial.InsertEndChild(mass);
  TiXmlElement tensor("inertia");
  tensor.SetAttribute("ixx", round_trip_text(about_com(0, 0)));
  tensor.SetAttribute("ixy", round_trip_text(about_com(0, 1)));
  tensor.SetAttribute("ixz", round_trip_text(about_com(0, 2)));
  tensor.SetAttribute("iyy", round_trip_text(about_com(1, 1)));
  tensor.SetAttribute("iyz", round_trip_text(about_com(1, 2)));
  tensor.SetAttribute("izz", round_trip_text(about_com(2, 2)));
  inertial.InsertEndChild(tensor);
  return inertial;
}

/// The document parsed, or InputError("urdf") saying why it cannot be.
TiXmlElement* parse_robot(TiXmlDocument& document, const std::string& xml) {
  document.Parse(xml.c_str());
  if (document.Error()) throw InputError("urdf", std::string("the URDF document cannot be read: ") + document.ErrorDesc());
  TiXmlElement* robot = document.FirstChildElement("robot");
  if (!robot) throw InputError("urdf", "the document has no <robot> element");
  return robot;
}

/// `note` as a comment before <robot> (XML forbids "--" inside a comment, and a trailing "-": "- -" reads
/// the same), and the document as text.
std::string printed(TiXmlDocument& document, TiXmlElement* robot, const std::string& note) {
  if (!note.empty()) {
    std::string text = note;
    for (std::size_t at = text.find("--"); at != std::string::npos; at = text.find("--", at)) text.replace(at, 2, "- -");
    TiXmlComment comment(("\n" + text + "\n").c_str());
    document.InsertBeforeChild(robot, comment);
  }
  TiXmlPrinter printer;
  printer.SetIndent("  ");
  document.Accept(&printer);
  return printer.CStr();
}

}  // namespace

std::string write_identified_urdf(const std::string& xml, const Model& model, const ParameterLayout& layout,
                                  const Eigen::VectorXd& pi, const std::string& note) {
  const int n = model.joint_count();
  if (pi.size() != layout.size(n)) {
    throw InputError("parameters", "the parameter vector has " + std::to_string(pi.size()) + " entries, the robot " +
                                       std::to_string(layout.size(n)));
  }
  if (!pi.allFinite()) throw InputError("parameters", "the parameter vector holds a value that is not a finite number");
  TiXmlDocument document;
  TiXmlElement* robot = parse_robot(document, xml);
  auto links = named_children(robot, "link");
  auto joints = named_children(robot, "joint");

  for (int k = 0; k < n; ++k) {
    const Joint& joint = model.joints[static_cast<std::size_t>(k)];
    const Body& body = model.bodies[static_cast<std::size_t>(k)];
    const InertialParameters inertia = InertialParameters::from_vector(pi.segment<kInertialParametersPerBody>(kInertialParametersPerBody * k));
    const auto link = links.find(joint.link);
    if (link == links.end()) throw InputError("urdf", "the document has no link " + joint.link);
    replace_child(link->second, "inertial", inertial_element(inertia, "link " + joint.link));
    // The links merged into this body: their inertia is in the body's now.
    for (std::size_t m = 1; m < body.links.size(); ++m) {
      const auto merged = links.find(body.links[m]);
      if (merged == links.end()) continue;
      if (TiXmlElement* old = merged->second->FirstChildElement("inertial")) merged->second->RemoveChild(old);
    }

    const auto element = joints.find(joint.name);
    if (element == joints.end()) throw InputError("urdf", "the document has no joint " + joint.name);
    if (layout.viscous || layout.coulomb) {
      TiXmlElement dynamics("dynamics");
      if (const TiXmlElement* old = element->second->FirstChildElement("dynamics")) dynamics = *old;
      if (layout.viscous) dynamics.SetAttribute("damping", round_trip_text(pi[layout.viscous_begin(n) + k]));
      if (layout.coulomb) dynamics.SetAttribute("friction", round_trip_text(pi[layout.coulomb_begin(n) + k]));
      replace_child(element->second, "dynamics", dynamics);
    }
    if (layout.offset || layout.armature) {
      std::ostringstream note;
      note << " identified by manipid, no URDF element for them:";
      if (layout.offset) note << " torque offset fo = " << round_trip_text(pi[layout.offset_begin(n) + k]) << (joint.is_prismatic() ? " N;" : " N m;");
      if (layout.armature) note << " rotor inertia Ia = " << round_trip_text(pi[layout.armature_begin(n) + k]) << (joint.is_prismatic() ? " kg;" : " kg m^2;");
      note << " ";
      TiXmlComment comment(note.str().c_str());
      element->second->InsertEndChild(comment);
    }
  }
  return printed(document, robot, note);
}

std::string write_payload_urdf(const std::string& xml, const Model& model, const InertialParameters& payload,
                               const std::string& note) {
  TiXmlDocument document;
  TiXmlElement* robot = parse_robot(document, xml);
  const auto links = named_children(robot, "link");
  if (links.count(model.tip_link) == 0) throw InputError("urdf", "the document has no link " + model.tip_link);
  if (links.count(kPayloadLink) != 0 || named_children(robot, "joint").count(kPayloadJoint) != 0) {
    throw InputError("urdf", std::string("the document already has a link ") + kPayloadLink + " or a joint " +
                                 kPayloadJoint + ": write the payload into the arm's URDF without one");
  }
  TiXmlElement link("link");
  link.SetAttribute("name", kPayloadLink);
  link.InsertEndChild(inertial_element(payload, std::string("the payload")));
  TiXmlElement joint("joint");
  joint.SetAttribute("name", kPayloadJoint);
  joint.SetAttribute("type", "fixed");
  TiXmlElement parent("parent"), child("child"), origin("origin");
  parent.SetAttribute("link", model.tip_link);
  child.SetAttribute("link", kPayloadLink);
  origin.SetAttribute("xyz", "0 0 0");
  origin.SetAttribute("rpy", "0 0 0");
  joint.InsertEndChild(parent);
  joint.InsertEndChild(child);
  joint.InsertEndChild(origin);
  robot->InsertEndChild(link);
  robot->InsertEndChild(joint);
  return printed(document, robot, note);
}

}  // namespace manipid::robot
