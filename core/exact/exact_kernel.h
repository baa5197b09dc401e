#pragma once
// Private to the exact narrow phase: CGAL's kernels as the narrow phase uses them, a triangle as
// the simplex it really is, and the constructions of intersection segments (constructions.cpp).
#include "peelcd/core/exact/narrow_phase.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <utility>
#include <variant>

namespace peelcd::exact_detail {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using P3 = K::Point_3;
using S3 = K::Segment_3;
using T3 = K::Triangle_3;

inline P3 to_cgal(const Vec3& p) { return P3(p.x(), p.y(), p.z()); }

// A triangle as the simplex it really is: triangle, segment (collinear) or point (all equal).
using Simplex = std::variant<T3, S3, P3>;
Simplex simplex(const TriangleCorners& t);

// Segment of two crossing, non-coplanar triangles in double (sa: A's corners against B's plane,
// sb: B's against A's): false where double cannot place it (near-parallel planes, needles).
bool crossing_segment(const TriangleCorners& a, const TriangleCorners& b, const int sa[3], const int sb[3], Vec3& p,
                      Vec3& q);
// Two proper triangles in two planes, each straddling the other's plane, that meet in one point
// only (the planes' line leaves one where it enters the other): decided by exact constructions,
// for classify_contact(); the narrow phase decides the same from its predicates' signs
// (crossing_intersect() in narrow_phase.cpp), and the adversarial tests hold the two together.
bool meet_in_one_point(const TriangleCorners& a, const TriangleCorners& b, const int sa[3], const int sb[3]);
// Their segment constructed exactly and rounded once; false when they do not meet.
bool exact_crossing_segment(const TriangleCorners& a, const TriangleCorners& b, const int sa[3], const int sb[3],
                            Vec3& p, Vec3& q);
// The exact construction of the intersection of two simplices: its extreme points.
std::pair<Vec3, Vec3> exact_segment(const TriangleCorners& a, const TriangleCorners& b, const Simplex& sa,
                                    const Simplex& sb);

}  // namespace peelcd::exact_detail
