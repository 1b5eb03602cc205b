#include "WovenGlDrawer.hpp"
#include "WovenFabricEngine.hpp"
#include <core/Scene.hpp>
#include <GL/gl.h>
#include <algorithm>
#include <cmath>

namespace yade {

YADE_PLUGIN((WovenGlDrawer));

namespace {

// Strain to colour: blue (0 or slack) through green to red (maxStrain and above).
void strainColour(double e, double maxStrain)
{
	const double t = std::clamp(maxStrain > 0 ? e / maxStrain : 0.0, 0.0, 1.0);
	glColor3d(t < 0.5 ? 0.0 : 2 * (t - 0.5), t < 0.5 ? 2 * t : 2 * (1 - t), t < 0.5 ? 1 - 2 * t : 0.0);
}

struct V3 {
	double x, y, z;
	V3 operator+(const V3& o) const { return { x + o.x, y + o.y, z + o.z }; }
	V3 operator-(const V3& o) const { return { x - o.x, y - o.y, z - o.z }; }
	V3 operator*(double s) const { return { x * s, y * s, z * s }; }
	double dot(const V3& o) const { return x * o.x + y * o.y + z * o.z; }
	V3 cross(const V3& o) const { return { y * o.z - z * o.y, z * o.x - x * o.z, x * o.y - y * o.x }; }
	V3 unit() const
	{
		const double n = std::sqrt(dot(*this));
		return n > 0 ? (*this) * (1 / n) : V3 { 0, 0, 1 };
	}
};

} // namespace

void WovenGlDrawer::render()
{
	const int nseg = std::clamp(segments, 3, 64);
	for (const auto& eng : scene->engines) {
		const auto* w = dynamic_cast<const WovenFabricEngine*>(eng.get());
		if (!w || !w->fabric) continue;
		woven::hostTubes(*w->fabric, tubes_);
		const double* n = tubes_.nodes.data();
		auto pos = [&](int i) { return V3 { n[8 * i], n[8 * i + 1], n[8 * i + 2] }; };
		glDisable(GL_CULL_FACE);
		if (wire) {
			glDisable(GL_LIGHTING);
			glBegin(GL_LINES);
			for (std::size_t k = 0; k < tubes_.elements.size(); ++k) {
				const int a = tubes_.elements[k];
				strainColour(tubes_.strain[k], maxStrain);
				const V3 p = pos(a), q = pos(a + 1);
				glVertex3d(p.x, p.y, p.z);
				glVertex3d(q.x, q.y, q.z);
			}
			glEnd();
			glEnable(GL_LIGHTING);
			continue;
		}
		glEnable(GL_LIGHTING);
		glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
		glEnable(GL_COLOR_MATERIAL);
		for (std::size_t k = 0; k < tubes_.elements.size(); ++k) {
			const int a = tubes_.elements[k];
			const V3  t = (pos(a + 1) - pos(a)).unit();
			strainColour(tubes_.strain[k], maxStrain);
			glBegin(GL_QUAD_STRIP);
			for (int j = 0; j <= nseg; ++j) {
				const double th = 2 * M_PI * j / nseg, c = std::cos(th), s = std::sin(th);
				for (int end = 0; end < 2; ++end) {
					const int     i = a + end;
					const double* d = n + 8 * i;
					// The section's frame at this node, normal to the CP: minor axis m (the stored
					// direction without its component along the CP), major axis M = m x t.
					V3 m = V3 { d[5], d[6], d[7] };
					m    = (m - t * m.dot(t)).unit();
					const V3 M      = m.cross(t);
					const double A = scale * d[3], B = scale * d[4];
					const V3 off    = M * (A * c) + m * (B * s);
					// Normal of the ellipse (x/A)^2 + (y/B)^2 = 1 at this point.
					const V3 nrm = (M * (c / std::max(A, 1e-30)) + m * (s / std::max(B, 1e-30))).unit();
					const V3 p   = pos(i) + off;
					glNormal3d(nrm.x, nrm.y, nrm.z);
					glVertex3d(p.x, p.y, p.z);
				}
			}
			glEnd();
		}
	}
}

} // namespace yade
