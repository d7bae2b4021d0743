/* Finding the orange ball in a camera image (RGB, 3 bytes a pixel): controllers/ball_vision.py
 * in C, with the same numbers. */
#ifndef BALL_VISION_H
#define BALL_VISION_H

/* The orange pixels' centroid (*x, *y) and their number (*count); 0 when fewer than 4 are seen. */
int find_ball(const unsigned char *image, int width, int height, double *x, double *y, int *count);

/* Angles (rad) of a pixel from the optical axis: *left (to the left) and *up (upwards). */
void pixel_angles(double x, double y, int width, int height, double fov, double *left, double *up);

#endif
