/* A simulated hand holding a haptic device: a mass pulled towards a moving target by an arm (a
 * spring and a critical damper) and pushed by the force the device renders. Examples and tests
 * use it in place of a person and a device: feed its position to sh_haptic_step (or, through a
 * device mapping, to an adapter) and its next target and the rendered force back to it. */
#ifndef SOFTHAP_EXAMPLES_SIMULATED_HAND_H
#define SOFTHAP_EXAMPLES_SIMULATED_HAND_H

typedef struct simulated_hand {
    double x[3], v[3]; /* the hand (and the device's end-effector): m, m/s */
    double target[3];  /* where the arm pulls it now (m) */
    double mass;       /* kg */
    double stiffness;  /* the arm's spring (N/m) */
    double damping;    /* the arm's damper (N s/m): critical for mass and stiffness */
} simulated_hand;

/* A hand of mass (kg) on an arm of stiffness (N/m), at rest at start (m), its target there. */
void simulated_hand_init(simulated_hand* hand, const double start[3], double mass, double stiffness);

/* Moves the hand by dt (s) under the arm, pulling towards target (m, the target at the end of
 * the step; the arm's damper follows the target's velocity), and the device's force (N) on
 * it, by symplectic Euler. */
void simulated_hand_move(simulated_hand* hand, const double target[3], double dt, const double force[3]);

#endif
