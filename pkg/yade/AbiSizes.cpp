// sizeof of YADE's classes as this plugin was compiled against YADE's source with the detected
// definitions; tests/yade/abi_sizes.py compares them with the sizes Debian's libyade allocates.
#include <core/Body.hpp>
#include <core/Bound.hpp>
#include <core/Cell.hpp>
#include <core/Engine.hpp>
#include <core/GlobalEngine.hpp>
#include <core/IGeom.hpp>
#include <core/IPhys.hpp>
#include <core/Interaction.hpp>
#include <core/Material.hpp>
#include <core/Scene.hpp>
#include <core/Shape.hpp>
#include <core/State.hpp>
#include <core/Aabb.hpp>
#include <pkg/common/Box.hpp>
#include <core/Dispatching.hpp>
#include <core/InteractionLoop.hpp>
#include <pkg/common/ElastMat.hpp>
#include <pkg/common/InsertionSortCollider.hpp>
#include <pkg/common/PyRunner.hpp>
#include <pkg/common/Sphere.hpp>
#include <pkg/dem/FrictPhys.hpp>
#include <pkg/dem/NewtonIntegrator.hpp>
#include <pkg/dem/ScGeom.hpp>
#include <cstring>

#define WOVEN_ABI_CLASSES(X)                                                                                                                           \
	X(State)                                                                                                                                       \
	X(Scene)                                                                                                                                       \
	X(Body)                                                                                                                                        \
	X(Shape)                                                                                                                                       \
	X(Bound)                                                                                                                                       \
	X(Material)                                                                                                                                    \
	X(Interaction)                                                                                                                                 \
	X(IGeom)                                                                                                                                       \
	X(IPhys)                                                                                                                                       \
	X(Cell)                                                                                                                                        \
	X(GlobalEngine)                                                                                                                                \
	X(PyRunner)                                                                                                                                    \
	X(NewtonIntegrator)                                                                                                                            \
	X(InsertionSortCollider)                                                                                                                       \
	X(Sphere)                                                                                                                                      \
	X(Box)                                                                                                                                         \
	X(Aabb)                                                                                                                                        \
	X(ScGeom)                                                                                                                                      \
	X(FrictPhys)                                                                                                                                   \
	X(FrictMat)                                                                                                                                    \
	X(BoundDispatcher)                                                                                                                             \
	X(IGeomDispatcher)                                                                                                                             \
	X(InteractionLoop)

extern "C" {
/// sizeof(yade::NAME) in this plugin, -1 for a class not in the list.
long woven_yade_sizeof(const char* name)
{
#define WOVEN_ABI_CASE(C)                                                                                                                              \
	if (std::strcmp(name, #C) == 0) return static_cast<long>(sizeof(yade::C));
	WOVEN_ABI_CLASSES(WOVEN_ABI_CASE)
#undef WOVEN_ABI_CASE
	return -1;
}
/// The class names, space-separated.
const char* woven_yade_abi_classes()
{
#define WOVEN_ABI_NAME(C) #C " "
	return WOVEN_ABI_CLASSES(WOVEN_ABI_NAME);
#undef WOVEN_ABI_NAME
}
}
