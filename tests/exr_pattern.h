/* The texels tests/exr_write.cpp writes and test_scene.c expects back: channel
 * c of display texel (x, y), exact in half and float. */
#ifndef PB_TESTS_EXR_PATTERN_H
#define PB_TESTS_EXR_PATTERN_H

#define EXR_PATTERN_W 8
#define EXR_PATTERN_H 4

static inline float exr_pattern(int x, int y, int c)
{
    return 0.25f * (float)((1 + x + 10 * y) * (c + 1));
}

#endif
