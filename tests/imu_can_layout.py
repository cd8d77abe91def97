"""The DBC and mapping file of an IMU-like CAN logger, as the mapped-layout tests write them.

The logger the tests and ``tests/benchmarks/bench_can.py`` imitate sends one message per
sample time that carries a 16-bit frame counter and three int16 axes (0.01 m/s^2 a bit), a
layout without rigtools' DBC attributes, so a mapping file says which signals form which
channel; a slower message carries the rig's state. :func:`imu_dbc` writes the DBC,
:func:`imu_mapping` the mapping (``data_schemas/channel_mapping.schema.json``).

Importable by bare name under pytest (``tests/`` is on the path); ``bench_can.py`` run as a
script puts ``tests/`` on the path itself.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

__all__ = ["OIL_TEMP_SIGNAL", "imu_dbc", "imu_mapping"]

#: ``SG_`` line of the oil temperature (0.01 degC a bit, offset -40 degC) in the first two bytes.
OIL_TEMP_SIGNAL = ' SG_ OilTemp : 0|16@1+ (0.01,-40) [-40|615.35] "degC" Logger'


def imu_dbc(*, frame_id: int = 288, message: str = "IMU", counter: str = "Counter",
            slow_message: str = "Rig", slow_bytes: int = 4,
            slow_signals: Sequence[str] = (OIL_TEMP_SIGNAL,)) -> str:
    """DBC text: the IMU message (counter, ``AccX``/``AccY``/``AccZ``) and a slow message.

    Parameters
    ----------
    frame_id, message : int, str
        Identifier (11-bit) and name of the IMU message (8 bytes): ``counter`` (uint16) in
        bytes 0-1, then ``AccX``, ``AccY``, ``AccZ`` (int16, little-endian, 0.01 m/s^2).
    counter : str
        Name of the frame counter signal.
    slow_message, slow_bytes : str, int
        Name and length (bytes) of the slow message (identifier 768, sent by ``Logger``).
    slow_signals : sequence of str
        The ``SG_`` lines of the slow message, as written in the DBC.
    """
    imu = [f' SG_ {counter} : 0|16@1+ (1,0) [0|65535] "" Logger'] + [
        f' SG_ Acc{axis} : {16 * (k + 1)}|16@1- (0.01,0) [-327.68|327.67] "m/s^2" Logger'
        for k, axis in enumerate("XYZ")]
    return "\n".join([
        'VERSION ""', "", "NS_ :", "", "BS_:", "", "BU_: Imu Logger", "",
        f"BO_ {frame_id} {message}: 8 Imu", *imu, "",
        f"BO_ 768 {slow_message}: {slow_bytes} Logger", *slow_signals, ""])


def imu_mapping(channels: Mapping[str, str], *, message: str = "IMU",
                counter: str = "Counter", sample_rate_Hz: float = 25_600.0,
                slow: Sequence[tuple[str, str, str]] = ()) -> str:
    """Mapping file (TOML): one uniform channel per axis, fed by the IMU message, and slow ones.

    Parameters
    ----------
    channels : mapping of str to str
        Channel name by axis (``"X"``, ``"Y"``, ``"Z"``), in the order they are written.
    message, counter : str
        The IMU message and its counter signal (as in :func:`imu_dbc`).
    sample_rate_Hz : float
        Sample rate of the uniform channels (Hz).
    slow : sequence of (str, str, str)
        ``(name, message, signal)`` of each slow channel.
    """
    uniform = "".join(
        f'[[uniform]]\nchannel = "{name}"\nmessage = "{message}"\nsamples = ["Acc{axis}"]\n'
        f'counter = "{counter}"\nsample_rate_Hz = {sample_rate_Hz}\n\n'
        for axis, name in channels.items())
    return uniform + "\n".join(f'[[slow]]\nname = "{name}"\nmessage = "{msg}"\n'
                               f'signal = "{signal}"\n' for name, msg, signal in slow)
