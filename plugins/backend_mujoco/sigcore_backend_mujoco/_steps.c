/* sigcore's stepping loop in C: many MuJoCo steps in one call from Python, stopping as soon as Python has
 * something to look at. See steps.py for how it is built and called, and what it guarantees.
 *
 * Each step does exactly what MujocoBackend.step does in Python: mj_step, then the held entities' qpos written
 * back and their velocities zeroed. With track_contacts, the loop stops after the first step whose contacts (the
 * ordered geom pairs of data->contact) differ from those at the call's start, so that Python turns them into
 * contact events at that step; steps in between had the same contacts, which produce no events. */
#include <stdlib.h>
#include <string.h>
#include <mujoco/mjdata.h>
#include <mujoco/mjmodel.h>

typedef void (*sigcore_step_fn)(const mjModel*, mjData*);

static int same_contacts(const mjData* d, const int* geoms, int ncon) {
  if (d->ncon != ncon) return 0;
  for (int c = 0; c < ncon; c++) {
    if (d->contact[c].geom[0] != geoms[2 * c] || d->contact[c].geom[1] != geoms[2 * c + 1]) return 0;
  }
  return 1;
}

/* Take up to n steps; returns how many were taken (1..n), or -1 if memory for the contacts ran out (no step was
 * taken then). */
int sigcore_steps(sigcore_step_fn step, const mjModel* m, mjData* d, int n,
                  const long long* held_qpos, const double* held_values, int nqpos,
                  const long long* held_dofs, int ndofs, int track_contacts) {
  int ncon = 0;
  int* geoms = NULL;
  if (track_contacts) {
    ncon = d->ncon;
    geoms = (int*)malloc(sizeof(int) * 2 * (size_t)(ncon > 0 ? ncon : 1));
    if (!geoms) return -1;
    for (int c = 0; c < ncon; c++) {
      geoms[2 * c] = d->contact[c].geom[0];
      geoms[2 * c + 1] = d->contact[c].geom[1];
    }
  }
  int taken = 0;
  while (taken < n) {
    step(m, d);
    taken++;
    for (int i = 0; i < nqpos; i++) d->qpos[held_qpos[i]] = held_values[i];
    for (int i = 0; i < ndofs; i++) d->qvel[held_dofs[i]] = 0.0;
    if (track_contacts && !same_contacts(d, geoms, ncon)) break;
  }
  free(geoms);
  return taken;
}
