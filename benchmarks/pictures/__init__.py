"""Pictures for the docs, drawn rather than measured: ``env_pictures`` (the README's picture of the envs) and
``noise_figure`` (a LIDAR scan and a depth image, clean and under each noise profile).
"""
