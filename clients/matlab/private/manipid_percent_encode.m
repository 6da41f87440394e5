function text = manipid_percent_encode(text)
%MANIPID_PERCENT_ENCODE  (private) Text as a URL query value: every byte but A-Z a-z 0-9 - _ . ~ as %XX.
if isa(text, 'string'), text = char(text); end
if ~manipid_is_octave()
  bytes = unicode2native(text, 'UTF-8');   % MATLAB chars are UTF-16; Octave's are already UTF-8 bytes
else
  bytes = uint8(text);
end
text = char(bytes);
safe = (text >= 'A' & text <= 'Z') | (text >= 'a' & text <= 'z') | (text >= '0' & text <= '9') ...
       | text == '-' | text == '_' | text == '.' | text == '~';
if all(safe), return; end
parts = cell(1, numel(text));
for k = 1:numel(text)
  if safe(k)
    parts{k} = text(k);
  else
    parts{k} = sprintf('%%%02X', double(bytes(k)));
  end
end
text = [parts{:}];
end
