"""A PLC for client mode: a pymodbus TCP server holding 100 registers from 0 (or REGISTERS: 42 is a
PLC programmed for the map without HELD .. REGIONS).
usage: fake_plc.py PORT [REGISTERS]"""
import logging
import sys

from pymodbus.datastore import ModbusSequentialDataBlock, ModbusServerContext, ModbusSlaveContext
from pymodbus.server import StartTcpServer

logging.basicConfig(level=logging.CRITICAL)
logging.getLogger("pymodbus").setLevel(logging.CRITICAL)
registers = int(sys.argv[2]) if len(sys.argv) > 2 else 100
store = ModbusSlaveContext(hr=ModbusSequentialDataBlock(0, [0] * registers), zero_mode=True)
StartTcpServer(context=ModbusServerContext(slaves=store, single=True), address=("127.0.0.1", int(sys.argv[1])))
