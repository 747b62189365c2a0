/* The unit conversions of the steering CAN's signals (ssp/can/Bus36m.dbc: deg, km/h) to the
 * models' SI variables and back, the same doubles as the runner's network
 * (artibus.can.dbc._conversion: factor = to_SI(from) / to_SI(to), with to_SI(deg) = pi / 180
 * and to_SI(km/h) = 1 / 3.6), so a node's frames carry the bytes of today's bench. */
#ifndef ARTIBUS_LSBUS_UNITS_H
#define ARTIBUS_LSBUS_UNITS_H

#include <math.h>

#define DEG_TO_RAD ((M_PI / 180) / 1.0)     /* a received deg signal into a rad input */
#define RAD_TO_DEG (1.0 / (M_PI / 180))     /* a rad output into a deg signal */
#define KMH_TO_MS ((1 / 3.6) / 1.0)         /* a received km/h signal into an m/s input */
#define MS_TO_KMH (1.0 / (1 / 3.6))         /* an m/s output into a km/h signal */

#endif
