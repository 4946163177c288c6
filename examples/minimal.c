/* minimal.c - build a BVH over two hair segments and trace one ray. */
#define HAIROBB_IMPLEMENTATION
#include "../hairobb.h"
#include <math.h>
#include <stdio.h>

int main(void)
{
    /* two cubic Bezier segments of one strand: x, y, z, radius per control point */
    static const float vertices[] = {
        0.0f, 0.0f, 0.0f, 0.02f,   0.1f, 0.3f, 0.0f, 0.02f,   0.2f, 0.6f, 0.0f, 0.018f,  0.3f, 1.0f, 0.0f, 0.016f,
        0.3f, 1.0f, 0.0f, 0.016f,  0.4f, 1.4f, 0.0f, 0.014f,  0.6f, 1.7f, 0.0f, 0.01f,   0.8f, 2.0f, 0.0f, 0.005f,
    };
    static const uint32_t indices[] = {0, 4};   /* first control point of each segment */
    hairobb_bvh *bvh;
    hairobb_ray ray = {{0.2f, 0.6f, -5.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY, 0.0f};
    hairobb_hit hit;
    hairobb_result result = hairobb_build(vertices, 8, indices, 2, NULL, &bvh);
    if (result != HAIROBB_OK) {
        fprintf(stderr, "hairobb_build: %s\n", hairobb_result_string(result));
        return 1;
    }
    if (hairobb_intersect1(bvh, &ray, &hit))
        printf("hit segment %u at t = %.4f, u = %.3f, v = %.3f\n", hit.prim_id, hit.t, hit.u, hit.v);
    else
        printf("miss\n");
    printf("occluded: %d, BVH memory: %zu bytes\n", hairobb_occluded1(bvh, &ray), hairobb_memory_bytes(bvh));
    hairobb_free(bvh);
    return 0;
}
