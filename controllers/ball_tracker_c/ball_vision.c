/* controllers/ball_vision.py in C: the same tests on the same integers, the same arithmetic in
 * double (sums of pixel coordinates are exact, so their mean is numpy's to the bit). */
#include <math.h>

#include "ball_vision.h"

int find_ball(const unsigned char *image, int width, int height, double *x, double *y, int *count) {
    long sum_x = 0, sum_y = 0, n = 0;
    for (int row = 0; row < height; row++) {
        for (int column = 0; column < width; column++) {
            const unsigned char *pixel = image + 3 * (row * width + column);
            int r = pixel[0], g = pixel[1], b = pixel[2];
            if (r > 110 && r > 3 * g / 2 + 10 && g > 3 * b / 2) {
                sum_x += column;
                sum_y += row;
                n++;
            }
        }
    }
    if (n < 4) return 0;
    *x = (double)sum_x / n;
    *y = (double)sum_y / n;
    *count = (int)n;
    return 1;
}

void pixel_angles(double x, double y, int width, int height, double fov, double *left, double *up) {
    double focal = (width / 2.0) / tan(fov / 2);
    *left = atan((width / 2.0 - x - 0.5) / focal);
    *up = atan((height / 2.0 - y - 0.5) / focal);
}
