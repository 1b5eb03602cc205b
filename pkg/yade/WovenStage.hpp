// The settings of the collision stage of a WovenFabricEngine as YADE objects, one per stage of the
// design card: the CP shape with its elliptic sections, the OBB bound functor, the collider, the
// geometry functor, the contact physics and the impulse law. The engine holds one of each (as
// InteractionLoop holds its functors); they are not per-body or per-interaction objects (the fabric is
// no YADE bodies: docs/yade_native.md, Design). Setting an attribute changes the core stage's
// parameter at the engine's next step (or at O.save); reading one through the engine shows the core's
// value; O.save / O.load keep them. The core sees them only as plain numbers and names
// (woven::HostStageParams, pkg/engine/HostBridge.hpp).
#pragma once
#include "engine/HostBridge.hpp"
#include <lib/serialization/Serializable.hpp>

namespace yade {

class WovenCPShape : public Serializable {
public:
	// clang-format off
	YADE_CLASS_BASE_DOC_ATTRS(WovenCPShape, Serializable,
		"The yarn CP's cross-sections (woven's shape/Section and the flattening under contact; docs/collisions.md), as set on a WovenFabricEngine's collision stage (WovenFabricEngine.shape). Changes apply at the engine's next step.",
		((std::string, sectionRule, "constant_area", , "How a flattened section's semi-axes follow the flattening eps: 'constant_area' (a b = r0^2) or 'paper' (a = r0(1+eps), b = r0(1-eps))."))
		((Real, mcd, 0.6, , "Maximum cross-sectional deformation, in (0, 1) (paper: 0.5-0.7)."))
		((std::string, flattening, "geometric", , "What the sections do under contact: 'geometric' (flatten up to the MCD at no force), 'none' or 'springs' (flatten, pushing back with WovenPhys.sectionStiffness)."))
		((int, flattenPasses, 4, , "Re-tests of flattened contacts per step, >= 1."))
	);
	// clang-format on
};
REGISTER_SERIALIZABLE(WovenCPShape);

class WovenCPBound : public Serializable {
public:
	// clang-format off
	YADE_CLASS_BASE_DOC_ATTRS(WovenCPBound, Serializable,
		"The OBB bound functor of the yarn CPs (woven's bound/CPBound: an oriented box around each CP and its elliptic sections), as set on a WovenFabricEngine (WovenFabricEngine.bound).",
		((Real, margin, 1e-6, , "Added to every side of a CP's OBB [m] >= 0: contacts start this close."))
	);
	// clang-format on
};
REGISTER_SERIALIZABLE(WovenCPBound);

class WovenCollider : public Serializable {
public:
	// clang-format off
	YADE_CLASS_BASE_DOC_ATTRS(WovenCollider, Serializable,
		"The broad phase of the yarn CPs (woven's collider/), as set on a WovenFabricEngine (WovenFabricEngine.collider). Every kind finds the same pairs.",
		((std::string, kind, "tree", , "'tree' (an OBB tree per yarn, YarnTreeCollider), 'grid' (uniform grid of cells, GridCollider) or 'sap' (sweep and prune)."))
		((Real, skin, 5e-6, , "Verlet skin of the broad phase [m] >= 0: candidate pairs are kept while every CP's box stays inside its box grown by this (0: a broad phase every step)."))
		((int, selfExclude, 1, , "CPs of one yarn this many elements apart or closer never collide, >= 1 (raised per yarn to 1 + ceil(2 r0 / l0))."))
		((bool, yarnContacts, true, , "Contacts between yarns; False leaves only the contacts with coupled YADE bodies."))
		((int, threads, 0, , "Threads of the collision stage, in [0, 64] (0: OpenMP's count); any count gives the same bits."))
		((Real, cellSize, 0, Attr::readonly, "Cell of the grid collider's last broad phase [m] (as large as the largest CP box; 0: none yet)."))
	);
	// clang-format on
};
REGISTER_SERIALIZABLE(WovenCollider);

class WovenGeomFunctor : public Serializable {
public:
	// clang-format off
	YADE_CLASS_BASE_DOC_ATTRS(WovenGeomFunctor, Serializable,
		"The narrow phase of a CP pair (woven's geom/: static and moving SAT, gap functions), as set on a WovenFabricEngine (WovenFabricEngine.geom).",
		((std::string, model, "gap", , "'gap' (a gap function per contact kind, exact gradient rows, position projection) or 'paper' (the paper's Sections 4-5)."))
		((Real, cacheDistance, 1e-7, , "A pair's contact is carried to the next step while its sections are unchanged and its nodes moved together to within this [m] >= 0 (0: every pair tested every step)."))
	);
	// clang-format on
};
REGISTER_SERIALIZABLE(WovenGeomFunctor);

class WovenPhys : public Serializable {
public:
	// clang-format off
	YADE_CLASS_BASE_DOC_ATTRS(WovenPhys, Serializable,
		"The stiffnesses of the force responses (woven's law/NormalForces), as set on a WovenFabricEngine (WovenFabricEngine.phys): the penalty contacts (WovenImpulseLaw.response 'penalty') and the section springs (WovenCPShape.flattening 'springs').",
		((Real, penaltyStiffness, 1e5, , "Penalty stiffness k_p [N/m] > 0: F = k_p delta on a contact overlapping by delta."))
		((Real, penaltyDamping, 0.0, , "Damping ratio of the penalty contacts, in [0, 1)."))
		((Real, sectionStiffness, 1e4, , "Stiffness k_s [N/m] > 0 of one node section's spring (paper Eq. 7)."))
	);
	// clang-format on
};
REGISTER_SERIALIZABLE(WovenPhys);

class WovenImpulseLaw : public Serializable {
public:
	// clang-format off
	YADE_CLASS_BASE_DOC_ATTRS(WovenImpulseLaw, Serializable,
		"The contact law of the yarns (woven's law/ImpulseLaw, PositionProjection: Gauss-Seidel impulses over all contact rows at once, then the position projection), as set on a WovenFabricEngine (WovenFabricEngine.law).",
		((std::string, response, "impulse", , "'impulse' (Eq. 5 impulses) or 'penalty' (spring forces, WovenPhys)."))
		((Real, restitution, 0.0, , "Restitution e in [0, 1] (Eq. 5)."))
		((Real, friction, 0.0, , "Coulomb coefficient between yarns, in [0, 2] (0 with response 'penalty')."))
		((Real, bodyFriction, 0.0, , "Coulomb coefficient between a coupled YADE body and the yarns, in [0, 2]."))
		((Real, tolerance, 1e-6, , "Resting band and solver tolerance on the normal velocity [m/s] > 0."))
		((int, maxIterations, 50, , "Bound on the impulse sweeps per step, >= 1."))
		((std::string, sweepOrder, "sequential", , "Row order of the sweeps: 'sequential' (contact order), 'coloured' (rows of a colour on the threads) or 'blocked' (slabs of the ply on the threads, then the rows across them)."))
		((int, projectionSweeps, -1, , "Sweeps of the position projection after the drift, in [0, 50], or -1 (auto: 8 with model 'gap' and response 'impulse', else 0)."))
		((Real, projectionSlop, 0.5e-6, , "Overlap the projection leaves alone [m], in [0, 1e-3]."))
		((Real, projectionMaxMove, 10e-6, , "Most one contact moves a node in a projection [m], in (0, 1e-3]."))
		((Real, projectionCheck, 2e-6, , "Contacts still deeper than this after the flattening are projected out before the rows [m], in [0, 1e-3]; -1: no check."))
		((Real, positionCorrection, 0.2, , "Model 'paper': fraction of a residual overlap removed per step, in [0, 1]."))
		((Real, correctionSlop, 0.5e-6, , "Model 'paper': overlap the positional correction leaves alone [m] >= 0."))
	);
	// clang-format on
};
REGISTER_SERIALIZABLE(WovenImpulseLaw);

} // namespace yade
