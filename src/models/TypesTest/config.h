/* TypesTest: a test FMU of the runner with a variable of every FMI 2.0 type
 * (issue 15). Its variables are declared in modelDescription/TypesTest.xml. */
#ifndef CONFIG_H
#define CONFIG_H

/* Saved as FMU state: plain data, nothing on the heap. */
typedef struct {
    int steps;                          /* communication steps taken */
} ModelState;

#endif
