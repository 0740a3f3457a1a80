"""A finished run's figures written into Scene.caustic, for the panels to show."""


def record_run(props, job) -> None:
    """Show the finished `job`'s time and lamp rays in Scene.caustic `props`."""
    props.last_seconds = job.seconds
    props.last_lamp_rays = job.result.stats["lamp_rays"]
    props.last_refined = job.result.stats["lamp_rays_refined"]
