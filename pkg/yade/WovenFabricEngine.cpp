#include "WovenFabricEngine.hpp"
#include "Base64.hpp"
#include "core/Errors.hpp"
#include "engine/FabricEngine.hpp"
#include "engine/Snapshot.hpp"
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
	woven::CollisionStage* st = fabric->collisions();
	const Real             dt = scene->dt;
	// Coupled bodies in: pose x_n (rewound over the NewtonIntegrator's drift) and velocities v_{n+1/2}.
	// The same operations as _yade_step of the default build (py/woven_module.cpp), so the same bits.
	if (st) {
		for (woven::RigidBody& b : st->bodies) {
			const shared_ptr<Body>& body = Body::byId(static_cast<Body::id_t>(b.id), scene);
			if (!body) throw std::runtime_error("WovenFabricEngine: coupled body " + std::to_string(b.id) + " is not in O.bodies");
			const State& s   = *body->state;
			woven::Vec3  pos = s.pos;
			woven::Quat  ori = s.ori;
			const woven::Vec3 vel = s.vel, w = s.angVel;
			if (rewind) {
				pos -= dt * vel;
				const Real angle = w.norm() * dt;
				if (angle > 0) ori = (woven::Quat(Eigen::AngleAxis<Real>(-angle, w.normalized())) * ori).normalized();
			}
			b.pos = pos, b.ori = ori, b.vel = vel, b.angVel = w;
		}
	}
	try {
		fabric->step(dt);
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
	// Coupled bodies out: pose x_{n+1}, velocities, and the angular momentum YADE integrates an
	// aspherical body (a clump) by.
	if (st) {
		for (const woven::RigidBody& b : st->bodies) {
			if (!b.dynamic()) continue; // YADE moves kinematic bodies itself
			State& s = *Body::byId(static_cast<Body::id_t>(b.id), scene)->state;
			s.pos    = b.pos;
			s.ori    = b.ori;
			s.vel    = b.vel;
			s.angVel = b.angVel;
			const woven::Vec3 wl = b.ori.conjugate() * b.angVel;
			s.angMom             = woven::Vec3(b.ori * woven::Vec3(b.inertia.cwiseProduct(wl)));
		}
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

long WovenFabricEngine::coreId() const { return static_cast<long>(reinterpret_cast<std::uintptr_t>(&woven::engineSnapshot)); }

long WovenFabricEngine::nodes() const { return fabric ? static_cast<long>(fabric->fabric().nNodes()) : 0; }

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
