/* transport.c - the table of transports (see transport.h).  Add yours here. */
#include "transport.h"

#include <string.h>

#include "can_transport.h"
#include "csv_transport.h"
#include "modbus_transport.h"
#include "replay_transport.h"

const transport_t *const transport_table[] = {
    &replay_transport,  /* input: logged track replayed on engine time */
    &csv_transport,     /* output: setpoints to a CSV file per object */
    &stdout_transport,  /* output: setpoints of every object to stdout */
    &can_transport,     /* input and output: SocketCAN or a candump log */
    &modbus_transport,  /* input (waypoint block) and service (status, commands): Modbus TCP/RTU */
    NULL,
};

unsigned transport_count(void)
{
    unsigned n = 0;
    while (transport_table[n])
        n++;
    return n;
}

const transport_t *transport_find(const char *name)
{
    for (unsigned i = 0; transport_table[i]; i++)
        if (strcmp(transport_table[i]->name, name) == 0)
            return transport_table[i];
    return NULL;
}

int transport_index(const transport_t *t)
{
    for (unsigned i = 0; transport_table[i]; i++)
        if (transport_table[i] == t)
            return (int)i;
    return -1;
}
