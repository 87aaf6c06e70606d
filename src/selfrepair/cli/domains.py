"""``selfrepair domains``: the robots this installation knows (built-in, plug-ins, and files loaded
with ``--plugin``)."""


from selfrepair.cli._app import app, echo, echo_json
from selfrepair.cli._inputs import Json


@app.command()
def domains(
    as_json: Json = False,
) -> int:
    """List the robot domains this installation knows.

    One line each: name, actions, faults and a description.
    """
    from selfrepair.robots.registry import domain_names, get_domain

    rows: list[dict[str, str | int]] = []
    for name in domain_names():
        domain = get_domain(name)
        rows.append(
            {
                "name": name,
                "actions": len(domain.actions),
                "faults": len(domain.faults),
                "fault_sets": len(domain.fault_sets),
                "description": domain.description,
            }
        )
    if as_json:
        echo_json(rows)
        return 0
    width = max(len(str(r["name"])) for r in rows)
    for r in rows:
        echo(
            f"{r['name']:<{width}}  {r['actions']:>3} actions  {r['faults']:>3} faults  "
            f"{r['description']}"
        )
    return 0
