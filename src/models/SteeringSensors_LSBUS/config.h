/* SteeringSensors_LSBUS: the plant's steering sensors on the steering CAN (issue 24); its
 * variables in modelDescription/lsbus/SteeringSensors_LSBUS.xml, its frames in model_lsbus.c. */
#ifndef CONFIG_H
#define CONFIG_H

#include "lsbus_node.h"

/* plain data */
typedef struct {
    LsNode bus;             /* the bus terminal's state */
} ModelState;

#endif
