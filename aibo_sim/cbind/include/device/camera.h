/* The head camera, with the report's types and macros: camera_get_image returns the RGB
 * image, 3 bytes a pixel, row-major from the top left, valid until the next call. */
#ifndef AIBO_SIM_DEVICE_CAMERA_H
#define AIBO_SIM_DEVICE_CAMERA_H

#include <device/robot.h>

#ifdef __cplusplus
extern "C" {
#endif

void camera_enable(DeviceTag camera, unsigned short ms);
void camera_disable(DeviceTag camera);
unsigned char *camera_get_image(DeviceTag camera);
unsigned short camera_get_width(DeviceTag camera);
unsigned short camera_get_height(DeviceTag camera);
float camera_get_fov(DeviceTag camera);

#define camera_image_get_red(image,width,x,y) (image[3*((y)*(width)+(x))])
#define camera_image_get_green(image,width,x,y) (image[3*((y)*(width)+(x))+1])
#define camera_image_get_blue(image,width,x,y) (image[3*((y)*(width)+(x))+2])
/* The mean of the three channels, rounded down. */
#define camera_image_get_grey(image,width,x,y) \
    ((camera_image_get_red(image,width,x,y) + camera_image_get_green(image,width,x,y) \
      + camera_image_get_blue(image,width,x,y)) / 3)
#define camera_image_get_gray camera_image_get_grey

/* Extension (not in Webots): the camera's settings, Sony's values (OPEN-R's ocamparam*),
 * from the next camera frame on. */
#define CAMERA_WB_INDOOR 1     /* 2856 K */
#define CAMERA_WB_OUTDOOR 2    /* 6500 K */
#define CAMERA_WB_FL 3         /* 5000 K, the default */
#define CAMERA_GAIN_LOW 1      /* -6 dB */
#define CAMERA_GAIN_MID 2      /* 0 dB, the default */
#define CAMERA_GAIN_HIGH 3     /* +6 dB */
#define CAMERA_SHUTTER_SLOW 1  /* 1/50 s */
#define CAMERA_SHUTTER_MID 2   /* 1/100 s, the default */
#define CAMERA_SHUTTER_FAST 3  /* 1/200 s */
void camera_set_white_balance(DeviceTag camera, int value);
void camera_set_gain(DeviceTag camera, int value);
void camera_set_shutter_speed(DeviceTag camera, int value);

#ifdef __cplusplus
}
#endif

#endif
