// Independent reference for goniofit's RGL `.bsdf` reader: RGL's own loader, powitacq_rgb
// (github.com/rgl-epfl/brdf-loader, commit c9ea6f9f, BSD-3-Clause), compiled against this
// driver by tests/ref/rgl_reference.sh. Nothing of goniofit is used.
//
// For every file given, two kinds of rows (CSV on standard output):
//   grid:   every 7th point (θi, row, column order) of the rgb grid at each stored θi with
//           cos θi > 1e-6: the outgoing direction the loader's sampling maps that grid point
//           to (its VNDF warp gives the facet normal; ωi = (sin θi, 0, cos θi) reflected
//           about it), and the loader's eval (f_r · cos θo per channel) at (ωi, ωo).
//   random: 150 direction pairs drawn from a fixed-seed generator over both hemispheres
//           (isotropic: ωi at azimuth 0), and the loader's eval there.
// The loader is compiled with POWITACQ_CLIP_RGB 0: values as stored, negatives kept. The
// VNDF warp the grid rows use is built from the file as the loader's constructor builds it.
#define POWITACQ_IMPLEMENTATION 1
#define POWITACQ_CLIP_RGB 0
#include "powitacq_rgb.h"
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

using namespace powitacq_rgb;

static uint64_t state = 0x853c49e6748fea9bULL;
static double uniform() {  // xorshift64*, fixed seed
    state ^= state >> 12; state ^= state << 25; state ^= state >> 27;
    return double((state * 0x2545F4914F6CDD1DULL) >> 11) / 9007199254740992.0;
}

static void row(const char *kind, const std::string &name, long t, long r, long c,
                const Vector3f &wi, const Vector3f &wo, const Vector3f &f) {
    printf("%s,%s,%ld,%ld,%ld,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", kind,
           name.c_str(), t, r, c, wi.x(), wi.y(), wi.z(), wo.x(), wo.y(), wo.z(), f[0], f[1], f[2]);
}

static void grid_rows(const BRDF &brdf, const Tensor &tf, const std::string &name) {
    const Tensor::Field &ti = tf.field("theta_i"), &rgb = tf.field("rgb");
    const float *theta = (const float *) ti.data.get();
    size_t ny = rgb.shape[3], nx = rgb.shape[4];
    // The VNDF warp, built from the file exactly as the loader's BRDF constructor does.
    const Tensor::Field &phi = tf.field("phi_i"), &v = tf.field("vndf");
    Warp2D2 vndf(Vector2u(v.shape[3], v.shape[2]), (const float *) v.data.get(),
                 {{ (uint32_t) phi.shape[0], (uint32_t) ti.shape[0] }},
                 {{ (const float *) phi.data.get(), theta }});
    long k = 0;
    for (size_t t = 0; t < ti.shape[0]; ++t) {
        float theta_i = theta[t];
        Vector3f wi(std::sin(theta_i), 0.f, std::cos(theta_i));
        if (!(wi.z() > 1e-6f))
            continue;
        float params[2] = { 0.f, theta_i };
        for (size_t r = 0; r < ny; ++r)
            for (size_t c = 0; c < nx; ++c, ++k) {
                if (k % 7 != 0)
                    continue;
                Vector2f u(float(c) / float(nx - 1), float(r) / float(ny - 1));
                Vector2f u_wm = vndf.sample(u, params).first;
                float phi_m = u2phi(u_wm.y()), theta_m = u2theta(u_wm.x());
                Vector3f wm(std::cos(phi_m) * std::sin(theta_m),
                            std::sin(phi_m) * std::sin(theta_m), std::cos(theta_m));
                Vector3f wo = wm * 2.f * dot(wm, wi) - wi;
                if (wo.z() <= 0)
                    continue;
                row("grid", name, long(t), long(r), long(c), wi, wo, brdf.eval(wi, wo));
            }
    }
}

static void random_rows(const BRDF &brdf, const std::string &name) {
    for (int k = 0; k < 150; ++k) {
        double ti = std::acos(uniform()), to = std::acos(uniform()), po = 2 * M_PI * uniform();
        Vector3f wi(float(std::sin(ti)), 0.f, float(std::cos(ti)));
        Vector3f wo(float(std::sin(to) * std::cos(po)), float(std::sin(to) * std::sin(po)),
                    float(std::cos(to)));
        row("random", name, k, -1, -1, wi, wo, brdf.eval(wi, wo));
    }
}

int main(int argc, char **argv) {
    printf("kind,file,t,row,col,wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,fr_cos_r,fr_cos_g,fr_cos_b\n");
    for (int a = 1; a < argc; ++a) {
        std::string path = argv[a];
        std::string name = path.substr(path.find_last_of('/') + 1);
        BRDF brdf(path);
        Tensor tf(path);
        grid_rows(brdf, tf, name);
        random_rows(brdf, name);
    }
    return 0;
}
