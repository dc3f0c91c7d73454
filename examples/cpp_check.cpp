// cpp_check.cpp - compiles the header family, implementations included, as C++ (used by
// `make check-warnings`) and runs a tiny scene, built from scene-file text, through the API.
#define PDFTRACE_IMPLEMENTATION
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"
#ifdef PDFTRACE_OPENEXR
#define PDFTRACE_EXR_IMPLEMENTATION
#include "pdftrace_exr.h"
#endif
#ifdef PDFTRACE_PNG
#define PDFTRACE_PNG_IMPLEMENTATION
#include "pdftrace_png.h"
#endif

#include <cstdio>

int main()
{
    pt_scene *s = pt_scene_create();
    if (!s) return 1;
    int white = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    int light = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 1);
    int rc = white < 0 ? white : light;
    if (rc >= 0) rc = pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, white);
    if (rc >= 0) rc = pt_scene_add_quad(s, pt_v3(-1, 3, -1), pt_v3(2, 0, 0), pt_v3(0, 0, 2), light);
#ifdef PDFTRACE_EMBREE
    if (rc >= 0) rc = pt_scene_set_backend(s, PT_BACKEND_EMBREE); // section 5b, compiled as C++
#endif
    if (rc >= 0) rc = pt_scene_commit(s);
    pt_render_desc d = {};
    pt_image img = {};
    if (rc >= 0) {
        d.width = 8;
        d.height = 8;
        d.samples_per_pixel = 2;
        d.threads = 1;
        d.camera.look_from = pt_v3(0, 0, -5);
        rc = pt_render_image(s, &d, &img, NULL);
    }
    if (rc != PT_OK) std::fprintf(stderr, "cpp_check: %s\n", pt_result_string(rc));
    static const char text[] = "camera look_from 0 0 -5 look_at 0 0 0\nmaterial w lambertian 0.5 0.5 0.5\n"
                               "sphere 0 0 0 1 w\n";
    pt_display_desc shown = {1.0f, PT_TONEMAP_ACES};
    if (rc == PT_OK) rc = pt_image_apply_display(&img, &shown, &img);
#ifdef PDFTRACE_PNG
    char png_err[256];
    if (rc == PT_OK && pt_write_png(NULL, &img, png_err, sizeof png_err) != PT_ERROR_INVALID_ARGUMENT) rc = PT_ERROR_INVALID_STATE;
#endif
    pt_scenefile sf;
    char err[256];
    if (rc == PT_OK) {
        rc = pt_scenefile_parse(text, sizeof text - 1, "cpp_check", NULL, &sf, err, sizeof err);
        if (rc == PT_OK) pt_scenefile_free(&sf);
        else std::fprintf(stderr, "cpp_check: %s\n", err);
    }
    pt_image_free(&img);
    pt_scene_destroy(s);
    return rc == PT_OK ? 0 : 1;
}
