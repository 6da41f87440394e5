// urdf_writer.h — an identified parameter vector written back into the robot's URDF, for a simulator or a
// controller (what ROSdyn and FloBaRoID users ask for).
//
// The document is edited, not regenerated: it is read with TinyXML (Debian's libtinyxml, the XML library
// urdfdom itself reads with) and only these elements change —
//  - each moving body's <inertial>, on its joint's child link: the body's mass, its centre of mass as
//    <origin xyz> (rpy 0) and its inertia about the centre of mass in the link's axes (ixx … izz: tensor
//    entries). A body merged from several links (a flange, a sensor) carries the whole body's inertia on
//    the child link; the links merged into it lose their <inertial>, so the document has the same dynamics;
//  - each moving joint's <dynamics damping="fv" friction="fc"> when the layout estimates them.
// Everything else — visuals, collisions, limits, transmissions, <gazebo> tags, comments — stays as it
// was. The offset fo and the armature Ia have no URDF element: a comment on the joint records them.
//
// A URDF can only hold a physical body: a mass ≤ 0 or an inertia about the centre of mass that is not
// positive semi-definite is refused (InputError "parameters", naming the link) — identify with the
// physical-consistency option first.
#pragma once

#include "manipid/core/robot/model.h"
#include "manipid/core/robot/parameters.h"
#include "manipid/core/robot/urdf.h"

#include <Eigen/Core>

#include <string>

namespace manipid::robot {

/// `xml` (the document `model` was parsed from with `options`) with `pi` (layout order) written in, and
/// `note` (when not empty) as a comment before <robot>: where the values came from and what they determine.
/// Throws InputError("urdf") when the document cannot be read, InputError("parameters") for a size
/// mismatch or a body a URDF cannot hold.
std::string write_identified_urdf(const std::string& xml, const Model& model, const ParameterLayout& layout,
                                  const Eigen::VectorXd& pi, const std::string& note = {});

/// The link and the fixed joint write_payload_urdf() adds.
inline constexpr const char* kPayloadLink = "manipid_payload";
inline constexpr const char* kPayloadJoint = "manipid_payload_joint";

/// `xml` (the document `model` was parsed from) with a payload mounted on the tip link: a link kPayloadLink
/// holding `payload` (its parameters in the tip link's frame, robot/payload.h) and a fixed joint kPayloadJoint
/// from the tip link at the identity, so a parser that merges fixed links gives the tip body the payload's
/// inertia added; and `note` as write_identified_urdf's. Throws InputError("urdf") for an unreadable document
/// or one that already has such a link or joint, InputError("parameters") for a payload a URDF cannot hold.
std::string write_payload_urdf(const std::string& xml, const Model& model, const InertialParameters& payload,
                               const std::string& note = {});

}  // namespace manipid::robot
