// WovenFabricEngine: woven's fabric as a YADE GlobalEngine (the native build, docs/yade_native.md).
// It owns a woven::FabricEngine (the C++ core, the same object the script's woven.FabricEngine
// wraps) and makes one woven step of O.dt per YADE iteration, with the coupled YADE bodies read
// before and written after the step, as the PyRunner adapter of the default build does
// (py/woven/engine.py, _yade_step in py/woven_module.cpp) but without Python in the loop.
// O.save writes the whole fabric (woven::engineSnapshot, base64 in the hidden attribute `snapshot`),
// O.load rebuilds it: the loaded run continues bit for bit as the one that saved it.
#pragma once
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
	/// Build id of the core library this plugin calls (woven._native compares it with
	/// woven._woven._build_id(): equal only for the package of the same native build).
	std::string coreBuild() const;

	std::vector<woven::HostBody> bodies_; // coupled bodies of the step (scratch)

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
		,
		/*ctor*/,
		.def("adopt", &WovenFabricEngine::adopt, (boost::python::arg("engine")), "Takes the fabric of a woven.FabricEngine (the same object: the script keeps using it).")
		.add_property("fabric", &WovenFabricEngine::pyFabric, "The woven.FabricEngine this engine steps (None before adopt).")
		.add_property("nodes", &WovenFabricEngine::nodes, "Yarn nodes of the fabric (0 before adopt).")
		.add_property("coreBuild", &WovenFabricEngine::coreBuild, "Build id of the woven core library the plugin calls (woven._native checks that woven._woven is of the same build).")
	);
	// clang-format on
};
REGISTER_SERIALIZABLE(WovenFabricEngine);

} // namespace yade
