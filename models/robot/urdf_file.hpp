// URDF robot files, read through urdfdom (Debian liburdfdom-dev).
//
// A serial chain of revolute, continuous and prismatic joints becomes a
// RobotModel in modified DH form (Craig) between a base and a tool transform
// (robot_model.hpp): DH frame j has its z axis on joint j's axis, pointing
// along the URDF axis, so q_j is the URDF joint variable (an axis (0, 0, -1)
// turns the other way), and its x axis on the common normal to joint j+1's
// axis (parallel axes: the normal through the previous frame's origin). The
// URDF root link's frame is the base frame (gravity, Cartesian quantities).
// Fixed joints merge their child links into the parent body (mass, centre of
// mass, inertia by the parallel-axis theorem); links fixed to the root are
// ground and carry no dynamics. A link without <inertial> has no mass.
//
// A tree (a hand with gripper fingers, sensor branches) is simulated along
// one chain: the side file's `tip` names a link, and the chain is the path
// from the root to it. Every link off that path, and every link past the
// tip, merges into its nearest ancestor on the path as fixed mass, its
// moving joints held at a stated value: the side file's [held] value, else
// a mimic joint's multiplier x its leader's held value + offset, else 0 (or
// the limit nearest 0). Each is a provenance line (RobotModel::provenance).
// The flange is the side file's `flange` (any link of the last body, merged
// ones included), else the tip, else the end of the fixed links after the
// last moving joint when they do not branch.
//
// Read as published: a chain joint's <dynamics damping friction> (joint-side
// viscous and Coulomb friction, JointParams::damping and coulomb: the
// defaults of a scene's [friction], moved to the motor side there), unless
// the side file says `refuse_dynamics = true`; a <transmission>'s
// mechanicalReduction and motorInertia (urdf_transmission.hpp) as the gear
// ratio and rotor inertia, which the side file's [joint.NAME] overrides.
//
// Refused, each with a ConfigError naming the file, the line of the joint or
// link and what was expected: a tree without a tip (two moving joints
// leaving one rigid body: the message names the leaves a tip may be), a
// closed loop (a link that is the child of two joints), links not connected
// to the root, floating and planar joints, a mimic joint on the chain, an
// off-chain mimic joint whose leader is on the chain (its mass would move
// with it) without a [held] value, negative damping or friction, a zero
// axis, revolute or prismatic limits without lower < upper, non-finite
// numbers, a negative mass, and a body whose mass and inertia are no rigid
// body's (link_inertia.hpp) unless the side file says why. Ignored: visual
// and collision geometry, materials, calibration, safety controllers,
// transmissions that couple several joints (listed in the provenance), and
// the limits' effort and velocity.
//
// What URDF has no place for comes from an optional TOML side file next to it,
// the same path with ".toml" appended (puma560.urdf -> puma560.urdf.toml),
// read strictly (format in models/robots/README.md): per moving joint its
// rotor inertia and gear ratio (default: a <transmission>'s, else none and
// 1, a direct drive) and an inconsistent_inertia excuse; gravity in the root
// link's frame (default [0, 0, -9.81], z up as in ROS); the tip, the flange
// link, refuse_dynamics; [held] joint values; named poses.
//
// Before urdfdom (and TinyXML 2.6.2, the XML parser it is built with on
// Debian 12) sees the text, one linear pass over it refuses, naming the file
// and the line, what those parsers were found to mishandle (issue 32): a file
// above the limits below (50,000 nested elements crashed TinyXML's recursive
// parser, and fewer were slow; one element with 100,000 attributes was slower
// still, its duplicate check being quadratic; a chain of 300,000 fixed joints
// crashed urdfdom; timings: commit 6c0fa5f), a NUL byte (TinyXML would stop
// reading there), a control character,
// a byte sequence that is not UTF-8 (TinyXML steps over a multi-byte
// character by the length its first byte gives: past the end of the text
// when the character is truncated there), a byte order mark past the start
// (TinyXML's whitespace), and markup it reads differently from XML or that
// the pass cannot count exactly: an unclosed comment, CDATA section,
// processing instruction, tag or attribute value (TinyXML steps over the
// missing end tag's length past the end of the text), a '>' inside a
// processing instruction's quoted value, a <!DOCTYPE with an internal subset
// or another <!, an unquoted attribute value, a '<' not starting a tag,
// mismatched tags, a '&' that is not one of XML's five entities or a
// character reference (TinyXML searches the rest of the file for each "&#"'s
// ';': quadratic), and a loop of links through the joints (urdfdom links them
// by shared pointers and leaks the loop when it refuses the file).
#pragma once

#include <cstddef>
#include <string>

#include "models/dynamics/robot_model.hpp"

namespace pumasim {

// The pre-scan's limits. Each is far above what a robot description has:
// Universal Robots' ur3 ... ur20.urdf and a Franka Panda robot.urdf (their
// ROS description packages) are 14-31 KB, 200-608 elements, 5 levels deep
// (robot > link > visual > geometry > mesh), with at most 6 attributes on an
// element (<inertia ixx ... izz>) and 18-40 <joint> elements; published
// descriptions run to about 100 KB.
//
// 4 MiB: 40 times that, a quarter of the generic input cap (kMaxInputBytes,
// 16 MiB). The costliest of the 4 MiB files tried within the other limits,
// 60,000 elements of 13 short attributes each, urdfdom parses quickly and in
// modest memory (Debian 12's urdfdom 3.0.1 and TinyXML 2.6.2, without
// sanitizers; measured: commit 6c0fa5f).
inline constexpr std::size_t kMaxUrdfBytes = std::size_t{4} << 20;
// 64 levels, the root element being level 1: TinyXML parses each level with
// a recursive call, and a level costs time that grows with the depth.
inline constexpr int kMaxUrdfDepth = 64;
// 64 attributes on one element: TinyXML checks each new attribute against
// the element's others, a cost quadratic in their number.
inline constexpr int kMaxUrdfAttributes = 64;
// 65,536 elements in all (100 times the Panda file's): bounds the
// parsed document's memory and urdfdom's work whatever the file's size.
inline constexpr std::size_t kMaxUrdfElements = std::size_t{1} << 16;
// 1,024 <joint> elements, wherever they are (a <transmission> names its joint
// in one too): four per moving joint at the most pumasim simulates (256,
// checked after parsing), room for fixed sensor and tool frames; a chain of
// fixed joints is at most that long for urdfdom's tree of links.
inline constexpr std::size_t kMaxUrdfJointElements = 1024;

// True for a path ending in ".urdf".
bool is_urdf_path(const std::string& path);

// The side file of a URDF file: its path with ".toml" appended.
std::string urdf_side_file(const std::string& urdf_path);

// Loads a URDF file and its side file when there is one; ConfigError otherwise.
RobotModel load_urdf_file(const std::string& path);

}  // namespace pumasim
