// WovenFabricEngine: woven's fabric as a YADE GlobalEngine (the native build, docs/yade_native.md).
// It owns a woven::FabricEngine (the C++ core, the same object the script's woven.FabricEngine
// wraps) and makes one woven step of O.dt per YADE iteration, with the coupled YADE bodies read
// before and written after the step, as the PyRunner adapter of the default build does
// (py/woven/engine.py, _yade_step in py/woven_module.cpp) but without Python in the loop.
// O.save writes the whole fabric (woven::engineSnapshot, base64 in the hidden attribute `snapshot`),
// O.load rebuilds it: the loaded run continues bit for bit as the one that saved it.
#pragma once
#include "WovenStage.hpp"
#include "engine/HostBridge.hpp" // woven's engine as an opaque type: no woven class layout is seen here
#include <core/GlobalEngine.hpp>
#include <memory>
#include <string>
#include <vector>

namespace yade {

class WovenFabricEngine : public GlobalEngine {
public:
	std::shared_ptr<woven::FabricEngine> fabric; // the core's engine; shared with the woven.FabricEngine Python object

	void action() override;
	~WovenFabricEngine() override;
	/// Takes the core engine of a woven.FabricEngine Python object (the same object, not a copy).
	void adopt(const boost::python::object& engine);
	/// The woven.FabricEngine Python object of the fabric (None before adopt or a load).
	boost::python::object pyFabric();
	long nodes() const;
	bool collisionsOn() const;
	/// Build id of the core library this plugin calls (woven._native compares it with
	/// woven._woven._build_id(): equal only for the package of the same native build).
	std::string coreBuild() const;

	std::vector<woven::HostBody> bodies_; // coupled bodies of the step (scratch)

	/// Brings the stage objects (shape, bound, collider, geom, phys, law) and the core's collision
	/// stage together, field by field: an attribute changed since the last sync is a pending change
	/// (applied to the core when `apply`: at a step and at O.save), any other takes the core's value
	/// (so a change made through woven's Python API shows here; with `apply` and nothing changed, the
	/// per-step case, nothing is read). Throws woven::ParameterError naming
	/// the attribute (e.g. law.restitution) on a bad value, the core unchanged.
	void syncStage(bool apply);
	woven::HostStageParams synced_; // the values the stage objects had at the last sync
	bool haveSynced_ = false;       // false: the next sync takes every value from the core

	template <class T, shared_ptr<T> WovenFabricEngine::*M> static shared_ptr<T> stageGet(WovenFabricEngine& self)
	{
		self.syncStage(false);
		return self.*M;
	}
	template <class T, shared_ptr<T> WovenFabricEngine::*M> static void stageSet(WovenFabricEngine& self, const shared_ptr<T>& v)
	{
		if (!v) throw std::invalid_argument("WovenFabricEngine: a stage object cannot be None");
		self.*M = v; // its values that differ from the last sync are applied at the next step
	}

	void preSave(WovenFabricEngine&);
	void postSave(WovenFabricEngine&);
	void postLoad(WovenFabricEngine&);

	// clang-format off
	YADE_CLASS_BASE_DOC_ATTRS_CTOR_PY(WovenFabricEngine, GlobalEngine,
		"woven's yarn-level fabric (a woven.FabricEngine) stepped natively in YADE's loop: one woven step of O.dt per iteration, "
		"coupled bodies (woven.coupling) in and out. Put it after NewtonIntegrator (woven.attach does). "
		"O.save / O.load keep the whole fabric and continue bit for bit. Units SI.",
		((bool, rewind, true, , "Coupled bodies were already moved over this iteration's step by a NewtonIntegrator before this engine: take them back to x_n first (woven.attach sets it)."))
		((std::string, snapshot, "", Attr::hidden, "The fabric's bytes (woven::engineSnapshot, base64) while O.save writes them and until O.load has read them; empty otherwise."))
		((std::string, lastError, "", Attr::readonly, "Message of the exception that stopped the last step ('' if none)."))
		// The collision stage's settings (pkg/yade/WovenStage.hpp): saved with the engine, shown through
		// the properties below, which sync them with the core first.
		((shared_ptr<WovenCPShape>, shape, new WovenCPShape, Attr::hidden, "CP sections (WovenCPShape)."))
		((shared_ptr<WovenCPBound>, bound, new WovenCPBound, Attr::hidden, "OBB bound functor (WovenCPBound)."))
		((shared_ptr<WovenCollider>, collider, new WovenCollider, Attr::hidden, "Broad phase (WovenCollider)."))
		((shared_ptr<WovenGeomFunctor>, geom, new WovenGeomFunctor, Attr::hidden, "Narrow phase (WovenGeomFunctor)."))
		((shared_ptr<WovenPhys>, phys, new WovenPhys, Attr::hidden, "Stiffnesses of the force responses (WovenPhys)."))
		((shared_ptr<WovenImpulseLaw>, law, new WovenImpulseLaw, Attr::hidden, "Contact law (WovenImpulseLaw)."))
		,
		/*ctor*/,
		.def("adopt", &WovenFabricEngine::adopt, (boost::python::arg("engine")), "Takes the fabric of a woven.FabricEngine (the same object: the script keeps using it).")
		.add_property("fabric", &WovenFabricEngine::pyFabric, "The woven.FabricEngine this engine steps (None before adopt).")
		.add_property("nodes", &WovenFabricEngine::nodes, "Yarn nodes of the fabric (0 before adopt).")
		.add_property("shape", &stageGet<WovenCPShape, &WovenFabricEngine::shape>, &stageSet<WovenCPShape, &WovenFabricEngine::shape>, "The CP's elliptic sections and their flattening (WovenCPShape). Changed attributes apply at the engine's next step (or O.save); reading shows the fabric's collision stage (switched on by woven.contact.enable or FabricEngine.enable_collisions).")
		.add_property("bound", &stageGet<WovenCPBound, &WovenFabricEngine::bound>, &stageSet<WovenCPBound, &WovenFabricEngine::bound>, "The OBB bound functor (WovenCPBound). Changed attributes apply at the engine's next step (or O.save); reading shows the fabric's collision stage (switched on by woven.contact.enable or FabricEngine.enable_collisions).")
		.add_property("collider", &stageGet<WovenCollider, &WovenFabricEngine::collider>, &stageSet<WovenCollider, &WovenFabricEngine::collider>, "The broad phase (WovenCollider). Changed attributes apply at the engine's next step (or O.save); reading shows the fabric's collision stage (switched on by woven.contact.enable or FabricEngine.enable_collisions).")
		.add_property("geom", &stageGet<WovenGeomFunctor, &WovenFabricEngine::geom>, &stageSet<WovenGeomFunctor, &WovenFabricEngine::geom>, "The geometry functor (narrow phase) (WovenGeomFunctor). Changed attributes apply at the engine's next step (or O.save); reading shows the fabric's collision stage (switched on by woven.contact.enable or FabricEngine.enable_collisions).")
		.add_property("phys", &stageGet<WovenPhys, &WovenFabricEngine::phys>, &stageSet<WovenPhys, &WovenFabricEngine::phys>, "The stiffnesses of the force responses (WovenPhys). Changed attributes apply at the engine's next step (or O.save); reading shows the fabric's collision stage (switched on by woven.contact.enable or FabricEngine.enable_collisions).")
		.add_property("law", &stageGet<WovenImpulseLaw, &WovenFabricEngine::law>, &stageSet<WovenImpulseLaw, &WovenFabricEngine::law>, "The contact law (WovenImpulseLaw). Changed attributes apply at the engine's next step (or O.save); reading shows the fabric's collision stage (switched on by woven.contact.enable or FabricEngine.enable_collisions).")
		.add_property("collisions", &WovenFabricEngine::collisionsOn, "The fabric has a collision stage (False: the stage objects show the defaults and refuse changes).")
		.add_property("coreBuild", &WovenFabricEngine::coreBuild, "Build id of the woven core library the plugin calls (woven._native checks that woven._woven is of the same build).")
	);
	// clang-format on
};
REGISTER_SERIALIZABLE(WovenFabricEngine);

} // namespace yade
