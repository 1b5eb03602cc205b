#include "WovenFabricEngine.hpp"
#include "Base64.hpp"
#include "core/Errors.hpp"
#include <core/Scene.hpp>
#include <lib/pyutil/gil.hpp>
#include <cstdint>

namespace yade {

YADE_PLUGIN((WovenFabricEngine));

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

} // namespace

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
	snapshot = fabric ? woven::yadeplugin::base64Encode(woven::engineSnapshot(*fabric)) : std::string();
}

void WovenFabricEngine::postSave(WovenFabricEngine&) { snapshot.clear(); }

void WovenFabricEngine::postLoad(WovenFabricEngine&)
{
	if (snapshot.empty()) return;
	fabric = woven::restoreSnapshot(woven::yadeplugin::base64Decode(snapshot));
	snapshot.clear();
}

} // namespace yade
