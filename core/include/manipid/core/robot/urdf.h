// urdf.h — a robot Model (robot/model.h) from a URDF document, parsed by Debian's urdfdom.
//
// What becomes the model: the serial chain from the base link (default: the URDF's root) down to the
// tip link (default: the only leaf). Moving joints on it (revolute, continuous, prismatic) are the
// model's joints 1..n, from the base. Fixed joints are merged: every link rigidly attached to a body —
// on the chain (a tool flange) or on a side branch (a sensor) — adds its inertia to that body, moved
// through the fixed transforms; links rigidly attached to the base are the world and do not enter the
// dynamics. Bodies beyond a moving joint that is not on the chain (a gripper's fingers) are left out, and
// a warning names them.
//
// URDF conventions used (each one moves torques far beyond any tolerance when got wrong):
//  - origin rpy: fixed-axis roll, pitch, yaw, R = Rz(yaw) · Ry(pitch) · Rx(roll);
//  - a joint's transform is Trans(xyz) · R(rpy) · Rot(axis, q): the axis is in the joint's (child) frame;
//  - <inertial>: the mass, the centre of mass at origin xyz, and the inertia tensor about the centre of
//    mass in the frame rotated by origin rpy (so R I Rᵀ in link axes); ixy, ixz, iyz are tensor entries;
//  - <dynamics damping friction>: viscous and Coulomb friction (robot/parameters.h).
//
// Axes: a non-unit axis is normalised (the URDF specification asks for unit axes, and a rotation "by q
// about 2·z" has no other sensible meaning; KDL does the same) and a warning says so when its norm is off
// by more than 1e-6; a zero axis is an error.
//
// Errors: InputError (manipid/core/errors.h), one line, whose field() names the element at fault —
// "joint panda_joint3", "link link4" — or the option ("base", "tip", "gravity"); "urdf" when urdfdom
// names no element. urdfdom reports through console_bridge; while parsing, its messages are captured
// (under a process-wide lock) instead of printed, and any error it logs refuses the document, even one it
// then parses past (a malformed <inertial> would otherwise become a massless link). console_bridge's
// handler is process-global: messages other threads send through console_bridge during a parse are
// captured with it.
//
// No I/O here: read the file yourself and pass its text.
#pragma once

#include "manipid/core/robot/model.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace manipid::robot {

/// The frame UrdfOptions::gravity is given in.
enum class GravityFrame {
  /// The URDF's root link. When the base is not the root, gravity is rotated into the base's frame through
  /// the joints between, which must then all be fixed (a moving one would make gravity's direction in the
  /// base frame depend on a joint the model does not know): an InputError("base") otherwise.
  root,
  /// The base link (UrdfOptions::base).
  base,
};

struct UrdfOptions {
  /// The link fixed to the world: the chain starts at its first moving joint below. Default (empty): the
  /// URDF's root link.
  std::string base{};
  /// The link that ends the chain; it must be below `base`. Default (empty): the only leaf below the base;
  /// with several leaves an InputError("tip") lists them.
  std::string tip{};
  /// Acceleration of gravity, m/s², in `gravity_frame`. Default: 9.81 straight down −z. Some published
  /// models use the standard 9.80665 (a 2.6e-4 relative difference): set it here to match them.
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  GravityFrame gravity_frame = GravityFrame::root;
};

struct ParsedUrdf {
  Model model;
  /// One line each: massless links, left-out bodies, normalised axes, urdfdom's own warnings, ...
  std::vector<std::string> warnings;
};

/// The deepest element nesting and the most attributes on one element a URDF may have. Real URDFs nest
/// 5 deep (robot > link > visual > geometry > mesh; vendors' extensions a few more) and put at most ~10
/// attributes on an element; the XML parser underneath recurses per level (40,000 levels overflowed the
/// stack) and checks attributes pairwise (100,000 on one element took 50 s), so documents beyond these
/// bounds are refused before it sees them.
inline constexpr int kMaxUrdfDepth = 100;
inline constexpr int kMaxUrdfAttributes = 100;

/// Throws InputError("urdf") when `xml` nests elements deeper than kMaxUrdfDepth or puts more than
/// kMaxUrdfAttributes attributes on one element, naming the element and where it starts. One pass over
/// the text (comments, CDATA, processing instructions, the DOCTYPE and quoted attribute values skipped);
/// anything else malformed is left to the parser.
void check_urdf_shape(const std::string& xml);

/// Parses a URDF document (its text) into a Model. Throws InputError (one line, naming the element) for:
/// a document beyond check_urdf_shape's bounds, malformed XML or URDF, a kinematic loop, a floating or planar joint or a mimic joint on the chain (or a
/// mimic tag on a merged fixed joint), an unknown base or tip, a tip not below the base, no moving joint
/// between them, a zero or non-finite axis, a mass that is negative or outside 1e-6..1e6 kg (0 is a massless
/// link), an inertia entry beyond 1e6 kg·m² or about the centre of mass not positive semi-definite, negative
/// <dynamics> damping or friction, a negative velocity limit, lower limit above upper, non-finite numbers.
/// A velocity limit of 0 is a warning (an excitation cannot move the joint).
ParsedUrdf parse_urdf(const std::string& xml, const UrdfOptions& options = {});

}  // namespace manipid::robot
