// WovenGlDrawer: draws the yarns of every WovenFabricEngine in O.engines in YADE's 3D view (yade.qt)
// as tubes of their elliptic sections (semi-axes a, b and the minor axis' direction at each node,
// woven::hostTubes), coloured by strain. Add it with
//     from yade import qt; qt.Renderer().extraDrawers = [WovenGlDrawer()]
// (woven.view() in py/woven/_native.py does this and frames the fabric).
#pragma once
#include "engine/HostBridge.hpp"
#include <pkg/common/OpenGLRenderer.hpp>

namespace yade {

class WovenGlDrawer : public GlExtraDrawer {
public:
	void render() override;

	// clang-format off
	YADE_CLASS_BASE_DOC_ATTRS(WovenGlDrawer, GlExtraDrawer,
		"Draws woven's yarns (every WovenFabricEngine in O.engines) as tubes of their elliptic sections, coloured by strain (blue 0, red at maxStrain).",
		((int, segments, 12, , "Points around each section's ellipse (3..64)."))
		((Real, scale, 1.0, , "Factor on the section's semi-axes (1: true size) [-]."))
		((Real, maxStrain, 0.05, , "Strain shown in full red [-]; slack yarns are blue."))
		((bool, wire, false, , "Draw the CP axes as lines instead of tubes (fast, for large fabrics)."))
	);
	// clang-format on

private:
	woven::HostTubes tubes_;
};
REGISTER_SERIALIZABLE(WovenGlDrawer);

} // namespace yade
