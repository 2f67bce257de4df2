"""The simulation engine: the loop algorithm, compiled or on CasADi's virtual machine."""
