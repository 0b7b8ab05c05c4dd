// dqjulia/ball_bound.hpp - what every point of a small 8-D ball does: proves that they all
// escape, and bounds their distance estimate from below.
//
// The bake skips a block of voxels when it can prove that no point of it is on the surface. The
// distance estimate at the block's centre alone does not prove that: at the paper's small N it
// bounds the distance to the limit set, not to the N-iteration set (math.md), and it is not a
// bound far from the set. This bound is rigorous instead: it iterates the centre's orbit and
// carries a radius of uncertainty along it. For q within d of p,
//     |(q^2 + c) - (p^2 + c)| = |p e + e p + e^2| <= 2 |p| d + d^2      (e = q - p, |e| <= d),
// so every orbit starting in the ball stays within d_k of the centre's orbit at step k, each
// derivative product is at most the product of 2 (|p_k| + d_k), and a ball whose orbits all
// leave the bailout radius (|p_k| - d_k > R) lies outside the N-iteration set. The DE of each
// point is then at least 0.5 s ln s / D, with s >= R the least escaping norm and D the largest
// derivative, minimised over the iterations at which a point of the ball could escape.
// Cost: one orbit of at most N iterations, about the cost of evaluate().
#pragma once

#include "dqjulia/algebra.hpp"
#include "dqjulia/estimate.hpp"
#include "dqjulia/export.h"

namespace dqj {

struct BallBound {
    Escape centre;           ///< evaluate() at the centre
    bool allEscape = false;  ///< proven: every point of the ball escapes within N iterations
    double minDe = 0.0;      ///< if allEscape: every point's DE (8-D units) is at least this
};

/// The ball of points whose real part lies within `radiusA` of centre.a and whose dual part lies
/// within `radiusB` of centre.b (8-D units; the bake passes a 3-D radius times the slice's
/// stretch of each part).
DQJ_API BallBound boundBall(const Fractal& fractal, const DualQuat& centre, double radiusA, double radiusB);

}  // namespace dqj
