#include "WovenFabricEngine.hpp"
#include "Base64.hpp"
#include "core/Errors.hpp"
#include <core/Scene.hpp>
#include <lib/pyutil/gil.hpp>
#include <cstdint>

namespace yade {

YADE_PLUGIN((WovenFabricEngine)(WovenCPShape)(WovenCPBound)(WovenCollider)(WovenGeomFunctor)(WovenPhys)(WovenImpulseLaw));

namespace {

// woven.engine records the failure as the PyRunner adapter does (woven.engine.last_error), so the
// scene scripts tell an instability from other errors the same way in both builds.
void reportToPython(const char* kind, const std::exception& e, long step, long node, long element, const std::string& cause)
{
	gilLock lock;
	try {
		boost::python::import("woven._native").attr("_failed")(kind, std::string(e.what()), step, node, element, cause);
	} catch (const boost::python::error_already_set&) {
		PyErr_Clear(); // woven not imported (a scene loaded without it): the message still stops the run
	}
}

// The stage objects' attributes and the core's settings they stand for: (object, attribute,
// woven::HostStageParams field, the parameter's name in the core's messages, as enable_collisions calls it).
#define WOVEN_STAGE_FIELDS(F)                                                                                                   \
	F(shape, sectionRule, sectionRule, "section_rule")                                                                          \
	F(shape, mcd, mcd, "mcd")                                                                                                   \
	F(shape, flattening, flattening, "flattening")                                                                              \
	F(shape, flattenPasses, flattenPasses, "flatten_passes")                                                                    \
	F(bound, margin, margin, "margin")                                                                                          \
	F(collider, kind, broadPhase, "broad_phase")                                                                                \
	F(collider, skin, skin, "skin")                                                                                             \
	F(collider, selfExclude, selfExclude, "self_exclude")                                                                       \
	F(collider, yarnContacts, yarnContacts, "yarn_contacts")                                                                    \
	F(collider, threads, threads, "threads")                                                                                    \
	F(geom, model, model, "contact_model")                                                                                      \
	F(geom, cacheDistance, cacheDistance, "contact_cache")                                                                      \
	F(phys, penaltyStiffness, penaltyStiffness, "penalty_stiffness")                                                            \
	F(phys, penaltyDamping, penaltyDamping, "penalty_damping")                                                                  \
	F(phys, sectionStiffness, sectionStiffness, "section_stiffness")                                                            \
	F(law, response, response, "response")                                                                                      \
	F(law, restitution, restitution, "restitution")                                                                             \
	F(law, friction, friction, "friction")                                                                                      \
	F(law, bodyFriction, bodyFriction, "body_friction")                                                                         \
	F(law, tolerance, tolerance, "tolerance")                                                                                   \
	F(law, maxIterations, maxIterations, "max_iterations")                                                                      \
	F(law, sweepOrder, sweepOrder, "sweep_order")                                                                               \
	F(law, projectionSweeps, projectionSweeps, "projection_sweeps")                                                             \
	F(law, projectionSlop, projectionSlop, "projection_slop")                                                                   \
	F(law, projectionMaxMove, projectionMaxMove, "projection_max_move")                                                         \
	F(law, projectionCheck, projectionCheck, "projection_check")                                                                \
	F(law, positionCorrection, positionCorrection, "position_correction")                                                       \
	F(law, correctionSlop, correctionSlop, "correction_slop")

// The core's message for a parameter ("friction = 3 is invalid: allowed ...") under the attribute's
// name ("law.friction = 3 is invalid: allowed ..."), so the user sees what to change on the YADE side.
woven::ParameterError renamed(const woven::ParameterError& e)
{
	std::string attr = e.parameter();
#define WOVEN_ATTR_NAME(obj, attr_, field, name)                                                                                \
	if (e.parameter() == name) attr = #obj "." #attr_;
	WOVEN_STAGE_FIELDS(WOVEN_ATTR_NAME)
#undef WOVEN_ATTR_NAME
	const std::string msg = e.what(), eq = " = ", inv = " is invalid: allowed ";
	const std::size_t a = msg.find(eq), b = msg.find(inv);
	if (a == std::string::npos || b == std::string::npos || b < a) return woven::ParameterError("WovenFabricEngine." + attr, "?", msg);
	return woven::ParameterError("WovenFabricEngine." + attr, msg.substr(a + eq.size(), b - a - eq.size()), msg.substr(b + inv.size()));
}

} // namespace

bool WovenFabricEngine::collisionsOn() const
{
	if (!fabric) return false;
	woven::HostStageParams p;
	woven::hostStageParams(*fabric, p);
	return p.collisions;
}

void WovenFabricEngine::syncStage(bool apply)
{
	if (!fabric) return;
	if (apply && haveSynced_) { // the per-step check: compares only, the core is read when something changed
		bool pending = false;
#define WOVEN_PENDING(obj, attr, field, name) pending = pending || obj->attr != synced_.field;
		WOVEN_STAGE_FIELDS(WOVEN_PENDING)
#undef WOVEN_PENDING
		if (!pending) return;
	}
	woven::HostStageParams core;
	woven::hostStageParams(*fabric, core);
	if (!haveSynced_) { // adopted: the objects show the fabric's settings, whatever they held
#define WOVEN_TAKE(obj, attr, field, name) obj->attr = core.field;
		WOVEN_STAGE_FIELDS(WOVEN_TAKE)
#undef WOVEN_TAKE
		synced_ = core, haveSynced_ = true;
	}
	// An attribute that differs from the last sync was set from YADE: it is wanted on the core. Any
	// other follows the core (changes made through the Python module show here).
	woven::HostStageParams want = core;
	bool pending = false;
#define WOVEN_MERGE(obj, attr, field, name)                                                                                     \
	if (obj->attr != synced_.field) want.field = obj->attr, pending = true;                                                     \
	else obj->attr = core.field, synced_.field = core.field;
	WOVEN_STAGE_FIELDS(WOVEN_MERGE)
#undef WOVEN_MERGE
	collider->cellSize = core.gridCell;
	if (!apply || !pending) return;
	try {
		woven::hostSetStageParams(*fabric, want); // validates first: on bad input nothing changes
	} catch (const woven::ParameterError& e) {
		throw renamed(e);
	}
	synced_ = want;
}

void WovenFabricEngine::action()
{
	if (!fabric) throw std::runtime_error("WovenFabricEngine: no fabric (woven.attach(engine) or WovenFabricEngine.adopt(engine) first)");
	// Coupled bodies in (pose x_n, rewound over the NewtonIntegrator's drift, velocities v_{n+1/2}),
	// one step, their new state out: woven::hostStep, the PyRunner adapter's operations in the core.
	woven::hostBodies(*fabric, bodies_);
	for (woven::HostBody& h : bodies_) {
		const shared_ptr<Body>& body = Body::byId(static_cast<Body::id_t>(h.id), scene);
		if (!body) throw std::runtime_error("WovenFabricEngine: coupled body " + std::to_string(h.id) + " is not in O.bodies");
		const State& s = *body->state;
		for (int i = 0; i < 3; ++i)
			h.pos[i] = s.pos[i], h.vel[i] = s.vel[i], h.angVel[i] = s.angVel[i];
		h.ori[0] = s.ori.x(), h.ori[1] = s.ori.y(), h.ori[2] = s.ori.z(), h.ori[3] = s.ori.w();
	}
	try {
		syncStage(true); // stage attributes set from YADE since the last step
		woven::hostStep(*fabric, scene->dt, bodies_, rewind);
	} catch (const woven::InstabilityError& e) {
		lastError = e.what();
		reportToPython("instability", e, e.step(), e.node(), e.element(), e.cause());
		throw std::runtime_error(e.what());
	} catch (const woven::ParameterError& e) {
		lastError = e.what();
		reportToPython("parameter", e, -1, -1, -1, e.parameter());
		throw std::runtime_error(e.what());
	} catch (const std::exception& e) {
		lastError = e.what();
		reportToPython("runtime", e, -1, -1, -1, "");
		throw;
	}
	for (const woven::HostBody& h : bodies_) {
		if (!h.dynamic) continue; // YADE moves kinematic bodies itself
		State& s = *Body::byId(static_cast<Body::id_t>(h.id), scene)->state;
		s.pos    = Vector3r(h.pos[0], h.pos[1], h.pos[2]);
		s.ori    = Quaternionr(h.ori[3], h.ori[0], h.ori[1], h.ori[2]);
		s.vel    = Vector3r(h.vel[0], h.vel[1], h.vel[2]);
		s.angVel = Vector3r(h.angVel[0], h.angVel[1], h.angVel[2]);
		s.angMom = Vector3r(h.angMom[0], h.angMom[1], h.angMom[2]);
	}
}

WovenFabricEngine::~WovenFabricEngine()
{
	// An adopted fabric is held through its Python object (Boost.Python's deleter drops a reference):
	// drop it with the GIL, and not at all once Python is finalized (a scene destroyed at exit).
	if (!fabric) return;
	if (Py_IsInitialized()) {
		gilLock lock;
		fabric.reset();
	} else {
		new std::shared_ptr<woven::FabricEngine>(std::move(fabric)); // leaked on purpose at exit
	}
}

void WovenFabricEngine::adopt(const boost::python::object& engine)
{
	boost::python::extract<std::shared_ptr<woven::FabricEngine>> x(engine);
	if (!x.check()) throw std::invalid_argument("engine = " + std::string(boost::python::extract<std::string>(boost::python::str(engine))()) + " is invalid: allowed a woven.FabricEngine");
	fabric = x();
	lastError.clear();
	haveSynced_ = false;
	syncStage(false); // the stage objects show the fabric's settings
}

boost::python::object WovenFabricEngine::pyFabric()
{
	if (!fabric) return boost::python::object();
	boost::python::import("woven._woven"); // registers the Python class of woven::FabricEngine
	return boost::python::object(fabric);
}

std::string WovenFabricEngine::coreBuild() const { return woven::coreBuildId(); }

long WovenFabricEngine::nodes() const { return fabric ? woven::hostNodes(*fabric) : 0; }

void WovenFabricEngine::preSave(WovenFabricEngine&)
{
	syncStage(false); // the saved stage objects and the saved fabric agree: the core's values,
	syncStage(true);  // then the changes made from YADE since the last step
	snapshot = fabric ? woven::yadeplugin::base64Encode(woven::engineSnapshot(*fabric)) : std::string();
}

void WovenFabricEngine::postSave(WovenFabricEngine&) { snapshot.clear(); }

void WovenFabricEngine::postLoad(WovenFabricEngine&)
{
	if (snapshot.empty()) return;
	fabric = woven::restoreSnapshot(woven::yadeplugin::base64Decode(snapshot));
	snapshot.clear();
	// The stage objects were saved synced with the fabric (preSave): they are the last sync, so only
	// later changes (none, unless the file was edited) are applied at the next step.
	if (!shape) shape = shared_ptr<WovenCPShape>(new WovenCPShape);
	if (!bound) bound = shared_ptr<WovenCPBound>(new WovenCPBound);
	if (!collider) collider = shared_ptr<WovenCollider>(new WovenCollider);
	if (!geom) geom = shared_ptr<WovenGeomFunctor>(new WovenGeomFunctor);
	if (!phys) phys = shared_ptr<WovenPhys>(new WovenPhys);
	if (!law) law = shared_ptr<WovenImpulseLaw>(new WovenImpulseLaw);
	woven::hostStageParams(*fabric, synced_);
#define WOVEN_LOADED(obj, attr, field, name) synced_.field = obj->attr;
	WOVEN_STAGE_FIELDS(WOVEN_LOADED)
#undef WOVEN_LOADED
	haveSynced_ = true;
}

} // namespace yade
